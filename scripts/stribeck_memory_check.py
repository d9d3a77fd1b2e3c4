#!/usr/bin/python3
"""Can a lagged Stribeck memory be identified from HESR's 0.25 Hz training sweep? (issue 6, diagnosis)

Reads the training records that `twinwatch friction-study --simulated --predictions P.csv` writes
(rows joint "J<k>-train": qd, residual torque) and fits, by linear least squares, the structure the
simulated truth itself has in sliding: tau = c0 + c1 qd + c2 h + c3 hd + c4 h s, with h, hd the
study's displacement-clock memory (the (alpha, beta) ParFam-H identified, passed below) and s the
Stribeck factor exp(-(qd/vs)^2) lagged in time by T (ds/dt = (exp(-(qd/vs)^2) - s)/T), the
truth's frictional lag. (vs, T) come from a grid, or are fixed at the truth's (an oracle, for
reference). Printed: the grid's choice, the fitted Stribeck drop c4 against the truth's Fs - Fc, and
the steady-sliding error of the fit against the truth's Stribeck curve at 0.01-0.5 rad/s, where the
closed loop's slow crawls run. The truth's parameters are used for that comparison only.

Needs Debian's python3 with numpy (apt-get install python3-numpy):
  build/twinwatch friction-study --simulated --seed 1 --trials 1 -q --predictions /tmp/pred1.csv
  /usr/bin/python3 scripts/stribeck_memory_check.py /tmp/pred1.csv
"""
import csv
import sys

import numpy as np

DT = 0.005  # the study's 200 Hz
# joint: (alpha, beta) of ParFam-H on seed 1 (the study prints them), then the truth of
# simulated_study_joints() in src/friction/study.cpp: Fc, Fs, vs, sigma2, lag
JOINTS = {
    "J1": ((1314.0, 345.4), (6.0, 8.0, 0.05, 5.0, 0.015)),
    "J2": ((960.1, 1e5), (9.0, 12.0, 0.08, 7.0, 0.025)),
    "J3": ((1259.0, 103.3), (3.0, 3.8, 0.04, 2.0, 0.010)),
}


def memory(qd, alpha, beta):
    """Displacement-clock h and hd (include/twinwatch/friction/hysteresis.hpp)."""
    h, hs, hds = 0.0, [], []
    for v in qd:
        target = np.tanh(beta * v)
        h = target + (h - target) * np.exp(-alpha * abs(v) * DT)
        hs.append(h)
        hds.append(alpha * abs(v) * (target - h))
    return np.array(hs), np.array(hds)


def lagged_stribeck(qd, vs, lag):
    s, out = 1.0, []
    keep = np.exp(-DT / lag) if lag > 0 else 0.0
    for v in qd:
        target = np.exp(-((v / vs) ** 2))
        s = target + (s - target) * keep
        out.append(s)
    return np.array(out)


def fit(qd, tau, h, hd, vs, lag):
    X = np.c_[np.ones_like(qd), qd, h, hd, h * lagged_stribeck(qd, vs, lag)]
    c, *_ = np.linalg.lstsq(X, tau, rcond=None)
    return c, float(np.mean((X @ c - tau) ** 2))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    rows = list(csv.DictReader(open(sys.argv[1])))
    for joint, ((alpha, beta), (Fc, Fs, vs0, sigma2, lag0)) in JOINTS.items():
        train = [r for r in rows if r["joint"] == joint + "-train"]
        if not train:
            sys.exit(f"{sys.argv[1]}: no rows of joint '{joint}-train' (write it with friction-study --simulated --predictions)")
        qd = np.array([float(r["qd"]) for r in train])
        tau = np.array([float(r["tau"]) for r in train])
        h, hd = memory(qd, alpha, beta)
        grid = [(fit(qd, tau, h, hd, vs, lag), vs, lag) for vs in (0.02, 0.03, 0.04, 0.05, 0.06, 0.08, 0.1, 0.13, 0.16, 0.2)
                for lag in (0.0, 0.005, 0.01, 0.015, 0.02, 0.025, 0.03, 0.04, 0.06)]
        (c_grid, mse_grid), vs_grid, lag_grid = min(grid, key=lambda g: g[0][1])
        c_true, mse_true = fit(qd, tau, h, hd, vs0, lag0)
        print(f"{joint}: truth vs {vs0} rad/s, lag {1000 * lag0:.0f} ms, Stribeck drop Fs - Fc {Fs - Fc:.2f} N·m")
        for label, c, vs, lag, mse in (("grid", c_grid, vs_grid, lag_grid, mse_grid), ("truth's vs, lag", c_true, vs0, lag0, mse_true)):
            errors = []
            for v in (0.01, 0.03, 0.05, 0.1, 0.5):
                model = c[0] + c[1] * v + c[2] + c[4] * np.exp(-((v / vs) ** 2))
                truth = Fc + (Fs - Fc) * np.exp(-((v / vs0) ** 2)) + sigma2 * v
                errors.append(f"{model - truth:+.2f}")
            print(f"  {label:16s} vs {vs:.3f}, lag {1000 * lag:4.0f} ms: drop c4 {c[4]:.2f} N·m, train mse {mse:.4f}; "
                  f"steady error at 0.01/0.03/0.05/0.1/0.5 rad/s: {' / '.join(errors)} N·m")


if __name__ == "__main__":
    main()
