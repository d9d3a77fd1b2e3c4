#!/usr/bin/env python3
"""Write the set of parts picked with no payload declared, held away from the flange (docs/validation.md,
session 52: "Where a part sits").

Three groups, one per point where the gripper holds its parts (flange frame, m): A (0, 0, 0.12),
B (0.04, 0, 0.10), C (0, 0.03, 0.17). Each group has 0.4, 0.7 and 1.0 kg parts on the figure-eight and on
the triangle (6 runs of 16 s, seeds from --seed), picked at 6.3-10.3 s with no declaration in the stream
(streams_payload: false). Score each group with the monitor told where its parts sit, and without:

    /usr/bin/python3 scripts/make_part_com_set.py scenarios/ur3e/part_com
    build/twinwatch evaluate scenarios/ur3e/part_com/A scenarios/ur3e/part_com/B scenarios/ur3e/part_com/C --twin T --json
    build/twinwatch evaluate scenarios/ur3e/part_com/A --twin T --part-com 0 0 0.12 --json      # B: 0.04 0 0.10, C: 0 0.03 0.17
"""
import argparse
import os

GROUPS = {"A": (0.0, 0.0, 0.12), "B": (0.04, 0.0, 0.10), "C": (0.0, 0.03, 0.17)}
PROGRAMS = {
    "fig": "{type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}",
    "tri": "{type: triangle, side: 0.15, speed: 0.2}",
}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="directory to write the groups A, B, C into")
    ap.add_argument("--seed", type=int, default=5201, help="seed of the first run (one per run)")
    a = ap.parse_args()
    i = 0
    for group, com in GROUPS.items():
        d = os.path.join(a.out, group)
        os.makedirs(d, exist_ok=True)
        for mass in (0.4, 0.7, 1.0):
            for prog, traj in PROGRAMS.items():
                i += 1
                name = f"part_{i}_{prog}_m{mass}"
                with open(os.path.join(d, f"part_{i}.yaml"), "w") as f:
                    f.write(f"# a {mass} kg part picked with no payload declared, held at {list(com)} m in the flange frame\n"
                            f"name: {name}\nrobot: ur3e\nseed: {a.seed + i - 1}\nduration: 16\nstreams_payload: false\n"
                            f"trajectory: {traj}\nfaults:\n"
                            f"  - {{type: payload_pick, onset: {6 + i % 5}.3, io_bit: 0, mass: {mass}, "
                            f"com: [{com[0]:g}, {com[1]:g}, {com[2]:g}]}}\n")
    print(f"{i} scenarios in {a.out}/A, B, C")


if __name__ == "__main__":
    main()
