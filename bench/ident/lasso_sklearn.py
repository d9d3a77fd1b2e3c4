#!/usr/bin/python3
"""scikit-learn LassoCV on the design written by `lasso_benchmark --write-data=DIR`.

Usage: lasso_sklearn.py DIR REPEATS TOL -> prints "wall <median s> cpu <median s>" and writes DIR/sklearn_<TOL>.txt
The columns are standardised first with the 1/n variance (glmnet's standardize=TRUE), the folds
are the same (PredefinedSplit), the alphas are glmnet's (100, eps = 1e-4); the coefficients are
mapped back to the original scale.
"""
import sys
import time

import numpy as np
from sklearn.linear_model import LassoCV
from sklearn.model_selection import PredefinedSplit

d, reps, tol = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
n, p, _ = (int(v) for v in open(f"{d}/meta.txt").read().split())
X = np.fromfile(f"{d}/X.f64", dtype="<f8").reshape((p, n)).T.copy()  # column-major on disk
y = np.fromfile(f"{d}/y.f64", dtype="<f8")
foldid = np.fromfile(f"{d}/foldid.i32", dtype="<i4")
times, cpu = [], []
for _ in range(reps):
    t0, c0 = time.perf_counter(), time.process_time()
    xm, xs = X.mean(axis=0), X.std(axis=0)  # np.std: 1/n variance
    Xs = (X - xm) / xs
    cv = LassoCV(cv=PredefinedSplit(foldid), n_alphas=100, eps=1e-4, tol=tol, max_iter=100000)
    cv.fit(Xs, y)
    times.append(time.perf_counter() - t0)
    cpu.append(time.process_time() - c0)
b = cv.coef_ / xs
a0 = cv.intercept_ - xm @ b
with open(f"{d}/sklearn_{sys.argv[3]}.txt", "w") as f:
    f.write(f"lambda_min {cv.alpha_:.17g}\n")
    f.write(f"nlambda {len(cv.alphas_)}\n")
    f.write("coef " + " ".join(f"{v:.17g}" for v in np.concatenate([[a0], b])) + "\n")
print(f"wall {np.median(times):.4f} cpu {np.median(cpu):.4f}")
