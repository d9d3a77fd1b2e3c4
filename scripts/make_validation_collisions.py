#!/usr/bin/env python3
"""Writes scenarios/ur3e/validation_collisions/*.yaml: a separate set of collision scenarios.

The monitor's collision detector and contact isolation are tuned on this set, so that the scenario
library's collisions (scenarios/ur3e/collision_*.yaml: links 2, 3 and 5, one force direction and one
point per link) stay a test set that nothing was tuned on. This set covers all six links, other seeds, onsets, points, directions, trajectories and
magnitudes (3-15 N·m joint-equivalent). Points are the link's centre of mass (data/robots/ur3e.json,
DH frame i, mapped to the body frame the simulator uses: body i = DH frame i-1 rotated by q_i,
p_body = Tz(d) Tx(a) Rx(alpha) p_DH) plus a random offset of up to 4 cm: a contact on the link's surface.
Rerun to regenerate (deterministic): python3 scripts/make_validation_collisions.py

`--held-out` writes scenarios/ur3e/heldout_collisions/ instead: the same construction with another
random stream, seeds 6000+, onsets and magnitudes (3, 4, 6, 10 N·m). Generated on 2026-11-23 after the
contact-isolation constants had been chosen on the library and the validation set, and used for
nothing but measuring them: python3 scripts/make_validation_collisions.py --held-out

`--held-out-2` writes scenarios/ur3e/heldout2_collisions/: 48 contacts (two per link and magnitude,
3, 5, 7, 12 N·m), seeds 8000+, another random stream. Generated on 2026-11-23 (session 7) after the
first held-out set had been looked at in detail to redesign the isolation (so that set is no longer
unseen); measured once with the final rule: python3 scripts/make_validation_collisions.py --held-out-2

`--held-out-3` writes scenarios/ur3e/heldout3_collisions/: 48 contacts (two per link and magnitude,
4, 6, 9, 14 N·m), seeds 9000+, another random stream. Generated on 2026-11-24 (session 9) after
held-out set 2 had been looked at three times; measured once with the rule of session 7 on the
session-8 twin: python3 scripts/make_validation_collisions.py --held-out-3

`--held-out-4` writes scenarios/ur3e/heldout4_collisions/: 48 contacts (two per link and magnitude,
3, 5, 8, 11 N·m), seeds 10000+, another random stream. Generated on 2026-11-24 (session 10) after the
report of a second contact link had been chosen on the validation and first held-out sets (sets 2 and
3 read at the same time); measured once: python3 scripts/make_validation_collisions.py --held-out-4

`--held-out-5` writes scenarios/ur3e/heldout5_collisions/: 48 contacts (two per link and magnitude,
3, 4, 6, 9 N·m), seeds 11000+, another random stream. Generated on 2026-11-24 (session 11) after the
contact link had become a Bayesian model choice (src/monitor/diagnosis.cpp, link_evidence), chosen
on the validation and first held-out sets with sets 2-4 read at the same time; measured once:
python3 scripts/make_validation_collisions.py --held-out-5

`--held-out-6` writes scenarios/ur3e/heldout6_collisions/: 48 contacts (two per link and magnitude,
3, 5, 7, 10 N·m), seeds 12000+, another random stream. Generated on 2026-11-24 (session 12) after a
joint at rest began to count up to the friction it holds (commit 832b045), chosen with sets 0-5 read;
measured once: python3 scripts/make_validation_collisions.py --held-out-6

`--held-out-7` writes scenarios/ur3e/heldout7_collisions/: 48 contacts (two per link and magnitude,
3, 4, 5, 8 N·m: half of them at or near the 3 N·m detection goal), seeds 13000+, another random
stream. Generated on 2026-11-24 (session 13) after the observer channel got its own debounce
(commit d7d630b), chosen with sets 0-6 read; measured once with the default debounce and with
--observer-raise-after 1: python3 scripts/make_validation_collisions.py --held-out-7

`--held-out-8` writes scenarios/ur3e/heldout8_collisions/: 54 contacts (three per link and magnitude,
3, 4, 6 N·m: a third of them at the 3 N·m detection goal), seeds 14000+, another random stream.
Generated on 2026-11-24 (session 15) after the observer's debounce became a per-joint choice on the
twin's healthy validation runs (choose_observer_debounce), chosen with sets 0-7 and the long runs
read; measured once: python3 scripts/make_validation_collisions.py --held-out-8
"""
import json
import math
import os
import random
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# flag -> (directory, magnitudes [N·m], repeats per link and magnitude, random seed, first noise seed)
SETS = {
    None: ("validation_collisions", [3, 5, 8, 15], 1, 20261123, 5000),
    "--held-out": ("heldout_collisions", [3, 4, 6, 10], 1, 7331, 6000),
    "--held-out-2": ("heldout2_collisions", [3, 5, 7, 12], 2, 4242, 8000),
    "--held-out-3": ("heldout3_collisions", [4, 6, 9, 14], 2, 9091, 9000),
    "--held-out-4": ("heldout4_collisions", [3, 5, 8, 11], 2, 5151, 10000),
    "--held-out-5": ("heldout5_collisions", [3, 4, 6, 9], 2, 60606, 11000),
    "--held-out-6": ("heldout6_collisions", [3, 5, 7, 10], 2, 80808, 12000),
    "--held-out-7": ("heldout7_collisions", [3, 4, 5, 8], 2, 31337, 13000),
    "--held-out-8": ("heldout8_collisions", [3, 4, 6], 3, 271828, 14000),
}
FLAG = next((a for a in sys.argv[1:] if a in SETS), None)
unknown = [a for a in sys.argv[1:] if a not in SETS]
if unknown:
    sys.exit(f"make_validation_collisions.py: unknown argument {unknown[0]!r}; expected one of {', '.join(k for k in SETS if k)}")
HELD_OUT = FLAG is not None
SET, MAGNITUDES, REPEATS, RANDOM_SEED, FIRST_SEED = SETS[FLAG]
OUT = os.path.join(ROOT, "scenarios", "ur3e", SET)
ROBOT = json.load(open(os.path.join(ROOT, "data", "robots", "ur3e.json")))

TRAJECTORIES = [
    ("figure_eight", "{type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}"),
    ("figure_eight_fast", "{type: figure_eight, size: [0.12, 0.08], period: 6, tilt: [0.3, 0.4, 0.5]}"),
    ("triangle", "{type: triangle, side: 0.15, speed: 0.2}"),
]


def main():
    rng = random.Random(RANDOM_SEED)
    os.makedirs(OUT, exist_ok=True)
    count = 0
    for link in range(1, 7):
        jd = ROBOT["joints"][link - 1]
        x, y, z = jd["com"]
        ca, sa = math.cos(jd["alpha"]), math.sin(jd["alpha"])
        com = [jd["a"] + x, ca * y - sa * z, jd["d"] + sa * y + ca * z]
        for m_idx, (mag, rep) in enumerate((m, r) for m in MAGNITUDES for r in range(REPEATS)):
            traj_name, traj = TRAJECTORIES[(link + m_idx) % len(TRAJECTORIES)]
            point = [round(c + rng.uniform(-0.04, 0.04), 3) for c in com]
            direction = [rng.gauss(0, 1) for _ in range(3)]
            norm = math.sqrt(sum(d * d for d in direction))
            direction = [round(d / norm, 3) for d in direction]
            onset = round(rng.uniform(6.0, 14.0), 3)
            seed = FIRST_SEED + 10 * link + m_idx
            payload = "payload: {mass: 0.5, com: [0, 0, 0.04]}\n" if (link + m_idx) % 2 == 0 else ""
            name = f"{'hcollision' if HELD_OUT else 'vcollision'}_{mag}Nm_link{link}" + (f"_{'abc'[rep]}" if REPEATS > 1 else "")
            text = (
                (f"# Held-out collision (measured only, never tuned on): a 50 ms pulse on link {link},\n" if HELD_OUT else
                 f"# Validation collision (tuning set; the library's collision_*.yaml is the test set): a 50 ms pulse on link {link},\n") +
                f"# peak joint-equivalent torque {mag} N·m, {traj_name}. Generated by scripts/make_validation_collisions.py.\n"
                f"name: {name}\nrobot: ur3e\nseed: {seed}\nduration: 16\ntrajectory: {traj}\n{payload}"
                f"faults:\n  - {{type: collision, link: {link}, onset: {onset}, magnitude: {mag}, duration: 0.05, "
                f"point: [{point[0]}, {point[1]}, {point[2]}], direction: [{direction[0]}, {direction[1]}, {direction[2]}]}}\n"
            )
            with open(os.path.join(OUT, name + ".yaml"), "w") as f:
                f.write(text)
            count += 1
    print(f"wrote {count} scenarios to {OUT}")


if __name__ == "__main__":
    main()
