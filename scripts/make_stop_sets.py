#!/usr/bin/env python3
"""Write scenario sets of the long runs' programs stopped and resumed (docs/validation.md, session 30:
"An arm the controller stops").

Each run is one of the long runs' nine programs (scenarios/ur3e/long: figure-eight with periods 6, 8
and 11 s, triangle at 0.12, 0.2 and 0.3 m/s, pick-and-place at three speeds), with or without the
0.5 kg payload, 45 s long, with two stops of the program (`stops:`, docs/scenarios.md): an
operator's pause, a protective stop or an emergency stop (power off, brakes, power on and brake
release before the program resumes), each held 1.5-8 s. Half of the runs then have a 3-5 N·m contact
on link 2, 3 or 5, 1.5-5 s after the second stop's resume ramp has ended.

    /usr/bin/python3 scripts/make_stop_sets.py scenarios/ur3e/stops --seed 30100 --runs 36
    /usr/bin/python3 scripts/make_stop_sets.py scenarios/ur3e/stops_heldout --seed 30500 --runs 36
    /usr/bin/python3 scripts/make_stop_sets.py scenarios/ur3e/stops_heldout2 --seed 30900 --runs 36 --stopping-times 0.15 0.3 0.6

Session 35 (streams without the controller's targets; the same runs, the second with each contact
moved into the first 0.02-0.28 s after the second stop's resume, its draw otherwise unchanged):

    /usr/bin/python3 scripts/make_stop_sets.py scenarios/ur3e/stops_heldout3 --seed 31300 --runs 36 --stopping-times 0.15 0.3 0.6 --no-targets
    /usr/bin/python3 scripts/make_stop_sets.py scenarios/ur3e/resume_contact --seed 31300 --runs 36 --stopping-times 0.15 0.3 0.6 --no-targets \
        --contact-after-resume 0.02 0.28 --contacts-only
"""
import argparse
import os
import random

P2P = ("[[-0.6, -1.4, 1.3, -1.5, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], "
       "[-0.6, -1.4, 1.3, -1.5, -1.3, 0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3], [0.6, -1.2, 1.45, -1.8, -1.85, -0.3], "
       "[0.6, -1.2, 1.45, -1.8, -1.85, -0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3]]")
FIG8 = "{{type: figure_eight, size: [0.12, 0.08], period: {}, tilt: [0.3, 0.4, 0.5]}}"
PROGRAMS = [
    ("fig8_6", FIG8.format(6)), ("fig8_8", FIG8.format(8)), ("fig8_11", FIG8.format(11)),
    ("tri_012", "{type: triangle, side: 0.15, speed: 0.12}"), ("tri_02", "{type: triangle, side: 0.15, speed: 0.2}"),
    ("tri_03", "{type: triangle, side: 0.15, speed: 0.3}"),
] + [(f"pick_{m}", f"{{type: point_to_point, waypoints: {P2P}, durations: [{m}, {m / 2}, {m}, {2 * m}, {m}, {m / 2}, {m}, {2 * m}]}}")
     for m in (0.6, 0.8, 1.2)]
HOLD = {"pause": (1.5, 4.0), "protective": (2.0, 5.0), "emergency": (4.0, 8.0)}
DURATION = 45.0


def main():
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("out")
    a.add_argument("--seed", type=int, required=True)
    a.add_argument("--runs", type=int, default=36)
    a.add_argument("--stopping-times", type=float, nargs="*", default=[],
                   help="draw each stop's stopping_time from these [s] (default: the simulator's 0.3 s)")
    a.add_argument("--no-targets", action="store_true", help="streams_targets: false (a logger without the controller's targets)")
    a.add_argument("--contact-after-resume", type=float, nargs=2, metavar=("LO", "HI"),
                   help="place each contact LO-HI s after the second stop's resume instead of 1.5-5 s after its ramp")
    a.add_argument("--contacts-only", action="store_true", help="write only the runs with a contact")
    o = a.parse_args()
    rng = random.Random(o.seed)
    os.makedirs(o.out, exist_ok=True)
    for k in range(o.runs):
        prog_name, traj = PROGRAMS[k % len(PROGRAMS)]
        payload = (k // len(PROGRAMS)) % 2 == 0
        kinds = [rng.choice(list(HOLD)) for _ in range(2)]
        stops, t = [], rng.uniform(5.0, 12.0)
        for kind in kinds:
            hold = rng.uniform(*HOLD[kind])
            ts = rng.choice(o.stopping_times) if o.stopping_times else 0.3
            extra = f", stopping_time: {ts}" if o.stopping_times else ""
            stops.append(f"  - {{kind: {kind}, at: {t:.3f}, hold: {hold:.3f}{extra}}}\n")
            end = t + hold + ts
            t = end + rng.uniform(4.0, 8.0)
        faults = ""
        if k % 2 == 1:
            link = rng.choice([2, 3, 5])
            onset = end + rng.uniform(1.5, 5.0)
            if o.contact_after_resume:  # (the same draw, mapped into the window: the rest of the set is unchanged)
                lo, hi = o.contact_after_resume
                onset = end - ts + lo + (hi - lo) * (onset - end - 1.5) / 3.5
            mag = rng.choice([3.0, 4.0, 5.0])
            d = [rng.uniform(-1, 1) for _ in range(3)]
            p = [round(rng.uniform(-0.04, 0.04), 3) for _ in range(3)]
            faults = (f"faults:\n  - {{type: collision, link: {link}, onset: {onset:.3f}, magnitude: {mag}, duration: 0.05, point: {p}, "
                      f"direction: [{d[0]:.3f}, {d[1]:.3f}, {d[2]:.3f}]}}\n")
        if o.contacts_only and not faults:
            continue
        name = f"stop_{k:02d}_{prog_name}_{'_'.join(kinds)}"
        with open(os.path.join(o.out, name + ".yaml"), "w") as f:
            f.write(f"# {prog_name}, {'0.5 kg payload' if payload else 'no payload'}, stops: {', '.join(kinds)}"
                    f"{', then a contact' if faults else ''} (scripts/make_stop_sets.py --seed {o.seed})\n")
            f.write(f"name: {name}\nrobot: ur3e\nseed: {o.seed + k}\nduration: {DURATION}\ntrajectory: {traj}\n")
            if payload:
                f.write("payload: {mass: 0.5, com: [0, 0, 0.04]}\n")
            f.write("stops:\n" + "".join(stops) + faults)
            if o.no_targets:
                f.write("streams_targets: false\n")


if __name__ == "__main__":
    main()
