#!/usr/bin/env Rscript
# cv.glmnet on the design written by `lasso_benchmark --write-data=DIR` (bench/ident/lasso_peers.sh).
# Usage: Rscript lasso_glmnet.R DIR REPEATS  -> prints "wall <median s> cpu <median s>" and writes DIR/glmnet.txt
suppressMessages(library(glmnet))
args <- commandArgs(trailingOnly = TRUE)
dir <- args[1]
reps <- as.integer(args[2])
meta <- scan(file.path(dir, "meta.txt"), quiet = TRUE)
n <- meta[1]; p <- meta[2]
x <- matrix(readBin(file.path(dir, "X.f64"), "double", n * p), n, p)  # column-major, like Eigen
y <- readBin(file.path(dir, "y.f64"), "double", n)
foldid <- readBin(file.path(dir, "foldid.i32"), "integer", n) + 1
times <- numeric(reps)
cpu <- numeric(reps)
for (r in seq_len(reps)) {
  t0 <- proc.time()
  cv <- cv.glmnet(x, y, foldid = foldid, nlambda = 100, standardize = TRUE, type.measure = "mse")
  t1 <- proc.time()
  times[r] <- t1[["elapsed"]] - t0[["elapsed"]]
  cpu[r] <- (t1[["user.self"]] + t1[["sys.self"]]) - (t0[["user.self"]] + t0[["sys.self"]])
}
b <- as.numeric(coef(cv, s = "lambda.min"))
out <- file(file.path(dir, "glmnet.txt"), "w")
writeLines(sprintf("lambda_min %.17g", cv$lambda.min), out)
writeLines(sprintf("lambda_1se %.17g", cv$lambda.1se), out)
writeLines(sprintf("nlambda %d", length(cv$lambda)), out)
writeLines(paste("coef", paste(sprintf("%.17g", b), collapse = " ")), out)
close(out)
cat(sprintf("wall %.4f cpu %.4f\n", median(times), median(cpu)))
