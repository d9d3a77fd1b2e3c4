#!/usr/bin/env python3
"""Write a set of joint resistances near the thresholds (docs/validation.md, session 40: "A
resistance read as a contact"): extra friction on one joint, 0.6-2x the evaluate twin's observer
threshold of that joint, on the library's programs (figure-eight with and without the 0.5 kg
payload, triangle, pick-and-place), half of them ending after 2-8 s (a binding that frees itself),
25 s each. Drawn once per seed; made after the change they check was chosen:

    /usr/bin/python3 scripts/make_resistance_sets.py scenarios/ur3e/resistance_heldout --seed 40100 --count 36
"""
import argparse
import os
import random

# per joint: the evaluate twin's observer threshold during the figure-eight [N·m] (monitor --trace)
THRESHOLD = [1.2, 1.43, 0.82, 0.45, 0.33, 0.34]
PROGRAMS = [
    ("figure_eight", "{type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}", True),
    ("figure_eight", "{type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}", False),
    ("triangle", "{type: triangle, side: 0.15, speed: 0.2}", False),
    ("pick_and_place", "{type: point_to_point, waypoints: [[-0.6, -1.4, 1.3, -1.5, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], "
     "[-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [-0.6, -1.4, 1.3, -1.5, -1.3, 0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3], "
     "[0.6, -1.2, 1.45, -1.8, -1.85, -0.3], [0.6, -1.2, 1.45, -1.8, -1.85, -0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3]], "
     "durations: [0.6, 0.3, 0.6, 1.2, 0.6, 0.3, 0.6, 1.2]}", False),
]


def main():
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("out")
    a.add_argument("--seed", type=int, required=True)
    a.add_argument("--count", type=int, default=36)
    o = a.parse_args()
    rng = random.Random(o.seed)
    os.makedirs(o.out, exist_ok=True)
    for k in range(o.count):
        joint = k % 6 + 1
        prog, traj, payload = PROGRAMS[(k // 6) % len(PROGRAMS)]
        magnitude = round(THRESHOLD[joint - 1] * rng.uniform(0.6, 2.0), 2)
        onset = round(rng.uniform(8.0, 14.0), 2)
        ends = k % 2 == 1
        end = round(onset + rng.uniform(2.0, 8.0), 2) if ends else None
        name = f"res_{k:02d}_j{joint}_{magnitude:g}_{prog}{'_payload' if payload else ''}{'_ends' if ends else ''}"
        with open(os.path.join(o.out, name + ".yaml"), "w") as f:
            f.write(f"# {magnitude:g} N·m of extra friction on J{joint} from {onset:g} s"
                    f"{f' to {end:g} s' if ends else ''}, {prog}{' with the 0.5 kg payload' if payload else ''} "
                    f"(scripts/make_resistance_sets.py --seed {o.seed})\n")
            f.write(f"name: {name}\nrobot: ur3e\nseed: {o.seed + k}\nduration: 25\ntrajectory: {traj}\n")
            if payload:
                f.write("payload: {mass: 0.5, com: [0, 0, 0.04]}\n")
            f.write(f"faults:\n  - {{type: resistance, joint: {joint}, onset: {onset:g}, ramp: 0.2, magnitude: {magnitude:g}"
                    f"{f', end: {end:g}' if ends else ''}}}\n")


if __name__ == "__main__":
    main()
