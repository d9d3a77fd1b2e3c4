#!/usr/bin/env python3
"""Writes scenarios/ur3e/long_heldout/*.yaml: the nominal long runs of scenarios/ur3e/long again
(same programs, speeds, payloads, durations and cold starts: 2.07 h) with other noise seeds
(20000 + the original's last three digits) and names prefixed long_heldout_.

A false-alarm test that nothing was chosen on: generated on 2026-11-24 (session 15) after the
observer's per-joint debounce (choose_observer_debounce) had been chosen with scenarios/ur3e/long
read; measured once. Deterministic: python3 scripts/make_heldout_long.py
"""
import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SRC = os.path.join(ROOT, "scenarios", "ur3e", "long")
OUT = os.path.join(ROOT, "scenarios", "ur3e", "long_heldout")


def main():
    if len(sys.argv) > 1:
        sys.exit(f"make_heldout_long.py: takes no arguments, got {sys.argv[1]!r}")
    files = sorted(glob.glob(os.path.join(SRC, "*.yaml")))
    if not files:
        sys.exit(f"make_heldout_long.py: no scenarios in {SRC}")
    os.makedirs(OUT, exist_ok=True)
    for path in files:
        text = open(path).read()
        seed = re.search(r"^seed: (\d+)$", text, re.M)
        name = re.search(r"^name: (long_\S+)$", text, re.M)
        if not seed or not name:
            sys.exit(f"{path}: expected lines 'name: long_...' and 'seed: N'")
        new_seed = 20000 + int(seed.group(1)) % 1000
        new_name = "long_heldout_" + name.group(1)[len("long_"):]
        text = text.replace(seed.group(0), f"seed: {new_seed}").replace(name.group(0), f"name: {new_name}")
        text = (f"# Held-out copy of scenarios/ur3e/long/{os.path.basename(path)} with another noise seed\n"
                f"# (scripts/make_heldout_long.py; measured only, nothing chosen on it).\n") + text
        with open(os.path.join(OUT, new_name + ".yaml"), "w") as f:
            f.write(text)
    print(f"wrote {len(files)} scenarios to {OUT}")


if __name__ == "__main__":
    main()
