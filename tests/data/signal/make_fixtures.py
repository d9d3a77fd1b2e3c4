#!/usr/bin/python3
# Reference values for tests/signal/savitzky_golay_test.cpp, from Debian's scipy (1.10):
#   /usr/bin/python3 tests/data/signal/make_fixtures.py
import numpy as np
from scipy.signal import savgol_filter
rng = np.random.default_rng(7)
t = np.arange(200) * 0.002
x = np.sin(2 * np.pi * 1.3 * t) + 0.3 * np.cos(2 * np.pi * 7 * t) + 0.05 * rng.standard_normal(t.size)
rows = []
for (w, p, d) in [(11, 3, 0), (11, 3, 1), (21, 4, 2), (7, 2, 0), (31, 5, 1)]:
    y = savgol_filter(x, w, p, deriv=d, delta=0.002, mode="interp")
    rows.append((w, p, d, y))
with open("tests/data/signal/savgol_scipy.csv", "w") as f:
    f.write("# x then one line per (window, order, deriv): w,p,d,y0,y1,...  (scipy.signal.savgol_filter, delta 0.002, mode interp)\n")
    f.write(",".join(repr(float(v)) for v in x) + "\n")
    for (w, p, d, y) in rows:
        f.write(f"{w},{p},{d}," + ",".join(repr(float(v)) for v in y) + "\n")
