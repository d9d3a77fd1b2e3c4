#!/usr/bin/python3
# Reference values for tests/signal/*_test.cpp (Savitzky–Golay, Butterworth, sosfiltfilt, firwin), from Debian's scipy (1.10):
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

# Butterworth designs (scipy.signal.butter(..., output='sos', fs=fs)) and zero-phase filtering
# (scipy.signal.sosfiltfilt, default padtype 'odd' and padlen) for tests/signal/butterworth_test.cpp
from scipy.signal import butter, sosfiltfilt, sosfilt_zi, firwin
designs = [(1, 10.0, 500.0), (2, 10.0, 500.0), (3, 25.0, 500.0), (4, 10.0, 500.0), (5, 2.0, 500.0),
           (6, 40.0, 500.0), (7, 120.0, 500.0), (8, 5.0, 1000.0), (4, 240.0, 500.0), (9, 0.5, 125.0)]
with open("tests/data/signal/butter_sos_scipy.csv", "w") as f:
    f.write("# order,cutoff_hz,fs_hz, then sos rows flattened [b0 b1 b2 a0 a1 a2]..., then sosfilt_zi flattened"
            "  (scipy.signal.butter(order, cutoff, output='sos', fs=fs); sosfilt_zi)\n")
    for (n, fc, fs) in designs:
        sos = butter(n, fc, output="sos", fs=fs)
        zi = sosfilt_zi(sos)
        f.write(f"{n},{fc!r},{fs!r}," + ",".join(repr(float(v)) for v in sos.ravel()) + ","
                + ",".join(repr(float(v)) for v in zi.ravel()) + "\n")
t = np.arange(600) * 0.002
x = (np.sin(2 * np.pi * 0.8 * t) + 0.4 * np.sin(2 * np.pi * 31 * t) + 0.3 * t
     + 0.05 * rng.standard_normal(t.size))
with open("tests/data/signal/sosfiltfilt_scipy.csv", "w") as f:
    f.write("# x (600 samples at 500 Hz), then order,cutoff_hz,fs_hz,n_used,y0,y1,...  (scipy.signal.sosfiltfilt"
            " of x[:n_used], padtype 'odd', default padlen)\n")
    f.write(",".join(repr(float(v)) for v in x) + "\n")
    for (n, fc, fs, used) in [(4, 10.0, 500.0, 600), (2, 10.0, 500.0, 600), (3, 25.0, 500.0, 600),
                              (5, 2.0, 500.0, 600), (8, 60.0, 500.0, 600), (4, 10.0, 500.0, 16),
                              (3, 10.0, 500.0, 13), (1, 50.0, 500.0, 7)]:
        y = sosfiltfilt(butter(n, fc, output="sos", fs=fs), x[:used])
        f.write(f"{n},{fc!r},{fs!r},{used}," + ",".join(repr(float(v)) for v in y) + "\n")

# Kaiser-window FIR low-pass designs (scipy.signal.firwin) for tests/signal/fir_test.cpp
with open("tests/data/signal/firwin_kaiser_scipy.csv", "w") as f:
    f.write("# numtaps,cutoff_hz,beta,fs_hz,h0,h1,...  (scipy.signal.firwin(numtaps, cutoff, window=('kaiser', beta), fs=fs))\n")
    for (nt, fc, beta, fs) in [(6, 10.0, 1.25, 117.0), (6, 40.0, 2.0, 500.0), (5, 50.0, 0.0, 500.0),
                               (11, 20.0, 5.0, 500.0), (31, 10.0, 8.6, 500.0), (64, 3.0, 4.0, 1000.0)]:
        h = firwin(nt, fc, window=("kaiser", beta), fs=fs)
        f.write(f"{nt},{fc!r},{beta!r},{fs!r}," + ",".join(repr(float(v)) for v in h) + "\n")
