#!/usr/bin/env python3
"""Add a half-sine torque pulse to one joint torque column of a recording (evaluation only).

A contact on a real arm with joint torque sensors shows in them as the external joint torque: the
sensor reads M qdd + h - tau_ext (docs/validation.md, "Joint torque sensors"). This adds -tau_ext of
a contact that loads one joint, a half sine of `magnitude` N·m peak over `duration` s from `onset`
(seconds from the file's first timestamp), to that joint's torque column of a real log, so that the
monitor's detection can be measured on the sensors' real noise. It leaves the motion as recorded
(a real contact also slows the arm a little: the twin, reading the recorded acceleration, sees the
pulse as it is here), and writes nothing else: no label column, the times go to stdout.

    /usr/bin/python3 scripts/inject_torque_pulse.py IN.csv OUT.csv --column tau2_Nm --onset 2.5 \\
        --magnitude 5 [--duration 0.05] [--time-column t_s]
"""
import argparse
import csv
import math
import sys


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("--column", required=True, help="the joint torque column to add the pulse to, as the file names it")
    ap.add_argument("--onset", type=float, required=True, help="start of the pulse [s] after the first timestamp")
    ap.add_argument("--magnitude", type=float, required=True, help="peak external joint torque [N·m] (the sensor reads minus it)")
    ap.add_argument("--duration", type=float, default=0.05, help="length of the half sine [s], default 0.05")
    ap.add_argument("--time-column", default="t_s", help="the time column [s], default t_s")
    a = ap.parse_args()
    if not a.duration > 0:
        sys.exit(f"--duration {a.duration}: expected a length > 0 s")
    with open(a.src, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        sys.exit(f"{a.src}: empty file")
    head = rows[0]
    for name in (a.column, a.time_column):
        if name not in head:
            sys.exit(f"{a.src}:1: no column '{name}' (the header has {', '.join(head)})")
    c, tc = head.index(a.column), head.index(a.time_column)
    t0 = float(rows[1][tc])
    hit = 0
    for line, r in enumerate(rows[1:], start=2):
        try:
            t = float(r[tc]) - t0
        except (ValueError, IndexError):
            sys.exit(f"{a.src}:{line}: column '{a.time_column}': expected a number, got '{r[tc] if tc < len(r) else ''}'")
        if a.onset <= t < a.onset + a.duration:
            r[c] = repr(float(r[c]) - a.magnitude * math.sin(math.pi * (t - a.onset) / a.duration))
            hit += 1
    if hit == 0:
        sys.exit(f"{a.src}: no sample between {a.onset} and {a.onset + a.duration} s after the first timestamp")
    with open(a.dst, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)
    print(f"{a.column}: -{a.magnitude:g} N·m half sine over {a.duration:g} s from {a.onset:g} s ({hit} samples)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
