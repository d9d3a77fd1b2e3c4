#!/usr/bin/env python3
"""Toggle one digital output bit of a twinwatch recording CSV, with no part behind it.

Used to check that a gripper output change alone (a vacuum blow-off, a gripper closing on nothing)
makes the monitor take no payload (docs/validation.md, session 28: "A part too light to raise an
alert"). The bit is set for `period` seconds, cleared for `period`, and so on from `start` on;
every other column is copied as it is. With --at-rests DELAY it is flipped instead DELAY seconds
into every rest of the program (every joint's target velocity zero), where a gripper acts in a
pick-and-place (session 29: "A part gripped or released while the arm rests"); a rest shorter than
DELAY is skipped.

    /usr/bin/python3 scripts/toggle_output_bit.py IN.csv OUT.csv [--bit 3] [--start 5] [--period 4]
    /usr/bin/python3 scripts/toggle_output_bit.py IN.csv OUT.csv --at-rests 0.1 [--start 5]
"""
import argparse
import csv
import sys


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src")
    ap.add_argument("dst")
    ap.add_argument("--bit", type=int, default=3, help="output bit to toggle (0-63), default 3")
    ap.add_argument("--start", type=float, default=5.0, help="first toggle [s], default 5")
    ap.add_argument("--period", type=float, default=4.0, help="time between toggles [s], default 4")
    ap.add_argument("--at-rests", type=float, default=None, metavar="DELAY",
                    help="flip the bit DELAY [s] into every rest from --start on (needs the target_qd_* columns)")
    a = ap.parse_args()
    if not 0 <= a.bit <= 63 or a.period <= 0:
        print(f"{sys.argv[0]}: --bit must be 0-63 and --period > 0", file=sys.stderr)
        return 2
    with open(a.src, newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    for name in ("timestamp", "actual_digital_output_bits"):
        if name not in header:
            print(f"{a.src}:1: no column '{name}' (a twinwatch recording has it)", file=sys.stderr)
            return 2
    ti, di = header.index("timestamp"), header.index("actual_digital_output_bits")
    tq = [i for i, name in enumerate(header) if name.startswith("target_qd_")]
    if a.at_rests is not None and not tq:
        print(f"{a.src}:1: --at-rests needs the target_qd_* columns", file=sys.stderr)
        return 2
    mask = 1 << a.bit
    flips, rest_since, flipped = 0, None, False
    for line, row in enumerate(rows[1:], start=2):
        try:
            t = float(row[ti])
            bits = int(float(row[di]))
            rests = all(abs(float(row[i])) < 1e-3 for i in tq)
        except (ValueError, IndexError):
            print(f"{a.src}:{line}: expected numbers in 'timestamp', 'actual_digital_output_bits' and 'target_qd_*'", file=sys.stderr)
            return 2
        if a.at_rests is None:
            k = int((t - a.start) // a.period) if t >= a.start else -1
            row[di] = str(bits | mask if k >= 0 and k % 2 == 0 else bits & ~mask)
            continue
        if not rests:
            rest_since, flipped = None, False
        elif rest_since is None:
            rest_since = t
        if rests and not flipped and t >= a.start and t - rest_since >= a.at_rests:
            flips += 1
            flipped = True
        row[di] = str(bits | mask if flips % 2 == 1 else bits & ~mask)
    with open(a.dst, "w", newline="") as f:
        csv.writer(f).writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
