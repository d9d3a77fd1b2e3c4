#!/usr/bin/env bash
# Lasso with 10-fold CV and 100 lambdas on ONE 20000 x 225 design: ours (Google Benchmark),
# R's cv.glmnet and scikit-learn's LassoCV, same data file, same folds, same standardisation, in
# one run; prints the times, the ratios and the agreement of the selections (docs/benchmarks.md).
#   bash bench/ident/lasso_peers.sh [BUILD_DIR]     (default build-bench, configured with -DBUILD_BENCHMARKS=ON)
# Peers (not project dependencies, not in scripts/setup.sh): apt-get install -y r-cran-glmnet python3-sklearn
# Single-threaded everywhere (BLAS threads pinned to 1) so that the comparison is per core.
set -euo pipefail
cd "$(dirname "$0")/../.."
B=${1:-build-bench}
REPS=${REPS:-3}
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
if ! Rscript -e 'library(glmnet)' >/dev/null 2>&1 || ! /usr/bin/python3 -c 'import sklearn' >/dev/null 2>&1; then
  if [[ $(id -u) -eq 0 ]]; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends r-cran-glmnet python3-sklearn
  else
    echo "lasso_peers: needs R's glmnet and scikit-learn: sudo apt-get install -y r-cran-glmnet python3-sklearn" >&2
    exit 1
  fi
fi
if [[ ! -x $B/bench/ident/lasso_benchmark ]]; then
  cmake -S . -B "$B" -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_BENCHMARKS=ON -DBUILD_TESTING=OFF >/dev/null
  cmake --build "$B" -j2 --target lasso_benchmark
fi
D=$(mktemp -d)
trap 'rm -rf "$D"' EXIT
"$B/bench/ident/lasso_benchmark" --write-data="$D"
echo "== ours (Google Benchmark) =="
"$B/bench/ident/lasso_benchmark" --data="$D" --result="$D/ours.txt" --benchmark_format=json >"$D/ours.json"
python3 - "$D/ours.json" <<'PY'
import json, sys
for b in json.load(open(sys.argv[1]))["benchmarks"]:
    print(f"  {b['name']:<28} {b['real_time']:10.1f} ms  ({b['iterations']} iterations)")
PY
echo "== R cv.glmnet(x, y, foldid, nlambda = 100, standardize = TRUE), thresh 1e-7 (median of $REPS) =="
Rscript bench/ident/lasso_glmnet.R "$D" "$REPS" | tee "$D/glmnet.time"
echo "== scikit-learn LassoCV(cv = same folds, n_alphas = 100, eps = 1e-4) on standardised X (median of $REPS) =="
/usr/bin/python3 bench/ident/lasso_sklearn.py "$D" "$REPS" 1e-4 | tee "$D/sk4.time"
/usr/bin/python3 bench/ident/lasso_sklearn.py "$D" "$REPS" 1e-7 | tee "$D/sk7.time"
python3 - "$D" <<'PY'
import json, sys
d = sys.argv[1]
def sel(name):
    out = {}
    for line in open(f"{d}/{name}"):
        k, *v = line.split()
        out[k] = [float(x) for x in v]
    return out
def times(name):
    w = open(f"{d}/{name}").read().split()
    return float(w[w.index("wall") + 1]), float(w[w.index("cpu") + 1])
ours = {b["name"].split("/")[0]: (b["real_time"] / 1e3, b["cpu_time"] / 1e3) for b in json.load(open(f"{d}/ours.json"))["benchmarks"]}
rows = [("ours, covariance updates", ours["BM_CvLasso_Covariance"]),
        ("ours, naive updates (baseline)", ours["BM_CvLasso_NaiveBaseline"]),
        ("R cv.glmnet", times("glmnet.time")),
        ("scikit-learn LassoCV, tol 1e-4 (default)", times("sk4.time")),
        ("scikit-learn LassoCV, tol 1e-7", times("sk7.time"))]
w0, c0 = rows[0][1]
print("\n| method | wall [s] | CPU [s] | ours / method, CPU | ours / method, wall |")
print("|---|---|---|---|---|")
for name, (w, c) in rows:
    print(f"| {name} | {w:.3f} | {c:.3f} | {c0 / c:.3f} | {w0 / w:.3f} |")
o, g = sel("ours.txt"), sel("glmnet.txt")
print("\nselection agreement (coefficients incl. intercept at lambda_min; max abs difference / max abs coefficient):")
for name, s in [("glmnet", g), ("sklearn tol 1e-4", sel("sklearn_1e-4.txt")), ("sklearn tol 1e-7", sel("sklearn_1e-7.txt"))]:
    dc = max(abs(a - b) for a, b in zip(o["coef"], s["coef"])) / max(abs(a) for a in o["coef"][1:])
    nz_o = sum(1 for a in o["coef"][1:] if a != 0.0)
    nz_s = sum(1 for a in s["coef"][1:] if a != 0.0)
    print(f"  vs {name:<17} lambda_min {o['lambda_min'][0]:.6g} / {s['lambda_min'][0]:.6g} (ratio {o['lambda_min'][0]/s['lambda_min'][0]:.6f}), "
          f"path length {int(o['nlambda'][0])} / {int(s['nlambda'][0])}, nonzero {nz_o} / {nz_s}, coef rel diff {dc:.2e}")
print(f"  lambda_1se ours {o['lambda_1se'][0]:.6g}, glmnet {g['lambda_1se'][0]:.6g}")
PY
