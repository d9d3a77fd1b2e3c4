#!/usr/bin/env python3
"""Write the slow-program sets (docs/validation.md, session 30: "A program run slower than its
thresholds saw"): the library figure-eight (its thresholds are learned at an 8 s period) run at
longer periods, as with the speed slider turned down, 80 s each (--duration), alternately with the 0.5 kg payload
and without.

    /usr/bin/python3 scripts/make_slow_sets.py scenarios/ur3e/slow --seed 4200 --periods 16 20 27 40
    /usr/bin/python3 scripts/make_slow_sets.py scenarios/ur3e/slow_heldout --seed 4300 --periods 14 18 24 32 48

Session 31 (the drive's direction read on the target), made after that change was chosen, measured once:

    /usr/bin/python3 scripts/make_slow_sets.py scenarios/ur3e/slow_heldout2 --seed 4400 --periods 15 22 36
    /usr/bin/python3 scripts/make_slow_sets.py scenarios/ur3e/long_slow_heldout --seed 31000 --periods 10 12 --duration 360
"""
import argparse
import os


def main():
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("out")
    a.add_argument("--seed", type=int, required=True)
    a.add_argument("--periods", type=float, nargs="+", required=True)
    a.add_argument("--duration", type=float, default=80.0)
    o = a.parse_args()
    os.makedirs(o.out, exist_ok=True)
    k = 0
    for period in o.periods:
        for payload in (True, False):
            name = f"slow_{period:g}_{'payload' if payload else 'none'}"
            with open(os.path.join(o.out, name + ".yaml"), "w") as f:
                f.write(f"# the library figure-eight at a {period:g} s period (8 s: the thresholds' own), "
                        f"{'0.5 kg payload' if payload else 'no payload'} (scripts/make_slow_sets.py --seed {o.seed})\n")
                f.write(f"name: {name}\nrobot: ur3e\nseed: {o.seed + k}\nduration: {o.duration:g}\n"
                        f"trajectory: {{type: figure_eight, size: [0.12, 0.08], period: {period:g}, tilt: [0.3, 0.4, 0.5]}}\n")
                if payload:
                    f.write("payload: {mass: 0.5, com: [0, 0, 0.04]}\n")
            k += 1


if __name__ == "__main__":
    main()
