#!/usr/bin/env Rscript
# cv.glmnet on the design written by `lasso_benchmark --write-data=DIR` (bench/ident/lasso_peers.sh).
# Usage: Rscript lasso_glmnet.R DIR REPEATS  -> prints "seconds <median>" and writes DIR/glmnet.txt
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
for (r in seq_len(reps)) {
  t0 <- proc.time()[["elapsed"]]
  cv <- cv.glmnet(x, y, foldid = foldid, nlambda = 100, standardize = TRUE, type.measure = "mse")
  times[r] <- proc.time()[["elapsed"]] - t0
}
b <- as.numeric(coef(cv, s = "lambda.min"))
out <- file(file.path(dir, "glmnet.txt"), "w")
writeLines(sprintf("lambda_min %.17g", cv$lambda.min), out)
writeLines(sprintf("lambda_1se %.17g", cv$lambda.1se), out)
writeLines(sprintf("nlambda %d", length(cv$lambda)), out)
writeLines(paste("coef", paste(sprintf("%.17g", b), collapse = " ")), out)
close(out)
cat(sprintf("seconds %.4f\n", median(times)))
