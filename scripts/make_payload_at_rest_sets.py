#!/usr/bin/env python3
"""Write the scenario sets of parts gripped or released while the arm rests (docs/validation.md,
session 29: "A part gripped or released while the arm rests").

A pick-and-place between two stations with rests of `dwell` seconds at each: in the second cycle a
part is picked `off` seconds into the rest at the pick station (negative: before the arm stops) and
released as far into the rest at the place station, with gripper output 0 changing there; no
payload is declared (streams_payload: false). Two kinds:

  rests    then a 3-5 N·m contact on links 2-6 in the third cycle's transfer, 0.3-1.2 s into it
           (scenarios/ur3e/payload_at_rest: layouts a b, seed 29100; .../payload_at_rest_heldout:
           layouts c a, seed 29500, --dwell 1.0 2.0 --off 0.1 0.35 -0.2 --mass 0.25 0.45 0.8)
  contact  one part change 0.2 s into a 1.5 s rest, then a contact on link 5 or 6 0.2-1.4 s after
           the arm moves on (scenarios/ur3e/payload_at_rest_contact, seed 29700)
  grip     on a figure-eight, a 0.3 or 0.6 kg part picked or dropped in motion at 8.3 s, a contact on
           link 5 or 6 0.05-0.3 s after the output changed (scenarios/ur3e/grip_contact, seed 29950)
  (and scenarios/ur3e/payload_at_rest_heldout2: rests, layout b, seed 29900, --dwell 1.2 2.2
  --off -0.3 -0.1 0.15 --mass 0.35 0.5 0.7)

    /usr/bin/python3 scripts/make_payload_at_rest_sets.py rests OUTDIR --seed 29100 --layouts a b
"""
import argparse
import os
import random
import sys

# (pick point, above it, place point, above it): joint positions [rad]
LAYOUTS = {
    "a": ([-0.6, -1.2, 1.45, -1.8, -1.3, 0.3], [-0.6, -1.4, 1.3, -1.5, -1.3, 0.3],
          [0.6, -1.2, 1.45, -1.8, -1.85, -0.3], [0.6, -1.4, 1.3, -1.5, -1.85, -0.3]),
    "b": ([-0.3, -1.5, 1.7, -1.8, -1.57, 0.0], [-0.3, -1.7, 1.5, -1.4, -1.57, 0.0],
          [0.9, -1.3, 1.2, -1.5, -1.2, 0.5], [0.9, -1.5, 1.0, -1.1, -1.2, 0.5]),
    "c": ([0.2, -1.0, 1.0, -1.6, -1.6, 1.0], [0.2, -1.25, 0.9, -1.2, -1.6, 1.0],
          [-0.8, -1.4, 1.6, -1.9, -1.4, -0.6], [-0.8, -1.6, 1.4, -1.5, -1.4, -0.6]),
}


def program(layout, dwell):
    a, a_up, b, b_up = LAYOUTS[layout]
    durations = [0.8, dwell, 0.8, 1.6, 0.8, dwell, 0.8, 1.6]
    return [a_up, a, a, a_up, b_up, b, b, b_up], durations


def contact(rng, link, onset):
    mag = rng.choice([3.0, 4.0, 5.0])
    d = [rng.uniform(-1, 1) for _ in range(3)]
    p = [round(rng.uniform(-0.04, 0.04), 3) for _ in range(3)]
    return (f"  - {{type: collision, link: {link}, onset: {onset:.3f}, magnitude: {mag}, duration: 0.05, point: {p}, "
            f"direction: [{d[0]:.3f}, {d[1]:.3f}, {d[2]:.3f}]}}\n")


def write(out, name, comment, seed, duration, waypoints, durations, faults, payload=None):
    with open(os.path.join(out, name + ".yaml"), "w") as f:
        f.write(f"# {comment}\nname: {name}\nrobot: ur3e\nseed: {seed}\nduration: {duration:.2f}\nstreams_payload: false\n")
        if payload:
            f.write(f"payload: {{mass: {payload}, com: [0, 0, 0.04]}}\n")
        f.write(f"trajectory: {{type: point_to_point, waypoints: {waypoints}, durations: {durations}}}\nfaults:\n{faults}")


def rests(a, rng):
    k = 0
    for layout in a.layouts:
        for dwell in a.dwell:
            for off in a.off:
                for mass in a.mass:
                    k += 1
                    if off >= dwell or off <= -0.8:
                        continue
                    wp, du = program(layout, dwell)
                    cycle = sum(du)
                    pick = cycle + 0.8 + off
                    drop = cycle + 0.8 + dwell + 0.8 + 1.6 + 0.8 + off
                    hit = 2 * cycle + 0.8 + dwell + 0.8 + rng.uniform(0.3, 1.2)
                    link = rng.choice([2, 3, 4, 5, 6])
                    faults = (f"  - {{type: payload_pick, onset: {pick:.3f}, io_bit: 0, mass: {mass}, com: [0, 0, 0.04]}}\n"
                              f"  - {{type: payload_loss, onset: {drop:.3f}, io_bit: 0}}\n" + contact(rng, link, hit))
                    write(a.out, f"rest_{layout}_d{dwell}_o{off}_m{mass}",
                          f"a part picked and dropped {off} s into {dwell} s rests at the stations (layout {layout}), then a contact",
                          a.seed + k, 2 * cycle + 0.8 + dwell + 0.8 + 1.6 + 1.0, wp, du, faults)


def contacts(a, rng):
    k = 0
    dwell = 1.5
    wp, du = program("a", dwell)
    cycle = sum(du)
    for what in ("pick", "drop"):
        for mass in (0.3, 0.6):
            for after in (0.2, 0.5, 0.9, 1.4):
                for link in (5, 6):
                    k += 1
                    rest = cycle + 0.8 if what == "pick" else cycle + 0.8 + dwell + 0.8 + 1.6 + 0.8
                    hit = rest + dwell + after
                    change = (f"  - {{type: payload_pick, onset: {rest + 0.2:.3f}, io_bit: 0, mass: {mass}, com: [0, 0, 0.04]}}\n"
                              if what == "pick" else f"  - {{type: payload_loss, onset: {rest + 0.2:.3f}, io_bit: 0}}\n")
                    write(a.out, f"rc_{what}_m{mass}_a{after}_l{link}",
                          f"a {mass} kg part {'picked' if what == 'pick' else 'released'} 0.2 s into a {dwell} s rest, then a contact "
                          f"on link {link} {after} s after the arm moves on",
                          a.seed + k, hit + 3.0, wp, du, change + contact(rng, link, hit), payload=mass if what == "drop" else None)


def grips(a, rng):
    k = 0
    fig8 = "{type: figure_eight, size: [0.12, 0.08], period: 8, tilt: [0.3, 0.4, 0.5]}"
    for what in ("pick", "drop"):
        for mass in (0.3, 0.6):
            for after in (0.05, 0.15, 0.3):
                for link in (5, 6):
                    k += 1
                    change = (f"  - {{type: payload_pick, onset: 8.3, io_bit: 0, mass: {mass}, com: [0, 0, 0.04]}}\n"
                              if what == "pick" else "  - {type: payload_loss, onset: 8.3, io_bit: 0}\n")
                    name = f"g_{what}_m{mass}_a{after}_l{link}"
                    with open(os.path.join(a.out, name + ".yaml"), "w") as f:
                        f.write(f"# a {mass} kg part {what} at 8.3 s in motion, a contact on link {link} {after} s after the output changed\n"
                                f"name: {name}\nrobot: ur3e\nseed: {a.seed + k}\nduration: 14\nstreams_payload: false\n")
                        if what == "drop":
                            f.write(f"payload: {{mass: {mass}, com: [0, 0, 0.04]}}\n")
                        f.write(f"trajectory: {fig8}\nfaults:\n{change}{contact(rng, link, 8.3 + after)}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("kind", choices=["rests", "contact", "grip"])
    ap.add_argument("out")
    ap.add_argument("--seed", type=int, default=29100)
    ap.add_argument("--layouts", nargs="+", default=["a", "b"], choices=sorted(LAYOUTS))
    ap.add_argument("--dwell", nargs="+", type=float, default=[0.8, 1.5, 2.5])
    ap.add_argument("--off", nargs="+", type=float, default=[0.05, 0.2, 0.5])
    ap.add_argument("--mass", nargs="+", type=float, default=[0.3, 0.6, 1.0])
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rng = random.Random(a.seed)
    {"rests": rests, "contact": contacts, "grip": grips}[a.kind](a, rng)
    return 0


if __name__ == "__main__":
    sys.exit(main())
