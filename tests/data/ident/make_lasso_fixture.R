#!/usr/bin/env Rscript
# Makes tests/data/ident/lasso_glmnet_fixture.txt: reference Lasso paths and cross-validation by
# R's glmnet (Debian: apt-get install -y r-cran-glmnet) for tests/ident/lasso_test.cpp.
#   Rscript tests/data/ident/make_lasso_fixture.R > tests/data/ident/lasso_glmnet_fixture.txt
# The file holds the data too, so the test needs neither R nor this script.
suppressMessages(library(glmnet))
set.seed(20261123)
out <- function(name, m) {
  m <- as.matrix(m)
  cat(name, nrow(m), ncol(m), "\n")
  write.table(format(m, digits = 17), quote = FALSE, row.names = FALSE, col.names = FALSE)
}
design <- function(n, p) {
  # correlated columns with different means and scales, a sparse truth and noise
  z <- matrix(rnorm(n * p), n, p)
  x <- z %*% chol(0.5^abs(outer(1:p, 1:p, "-")))
  x <- sweep(x, 2, runif(p, 0.1, 5), "*")
  x <- sweep(x, 2, runif(p, -3, 3), "+")
  b <- rep(0, p); b[c(1, 3, 7)] <- c(2, -1.5, 0.8)
  y <- 1.5 + x %*% b + rnorm(n, sd = 0.7)
  list(x = x, y = y)
}
case <- function(tag, n, p, standardize, intercept, nfolds) {
  d <- design(n, p)
  foldid <- sample(rep(seq(nfolds), length = n))
  fit <- glmnet(d$x, d$y, nlambda = 30, standardize = standardize, intercept = intercept, thresh = 1e-14)
  cv <- cv.glmnet(d$x, d$y, nlambda = 30, standardize = standardize, intercept = intercept, thresh = 1e-14,
                  foldid = foldid)
  cat("case", tag, n, p, as.integer(standardize), as.integer(intercept), "\n")
  out("x", d$x)
  out("y", d$y)
  out("foldid", foldid - 1)
  out("lambda", fit$lambda)
  out("a0", fit$a0)
  out("beta", as.matrix(fit$beta))
  out("cv_lambda", cv$lambda)
  out("cvm", cv$cvm)
  out("cvsd", cv$cvsd)
  out("lambda_min_1se", c(cv$lambda.min, cv$lambda.1se))
  # folds solved at the full path's lambdas (scikit-learn's way, LassoCvAlignment::FullLambda)
  cvf <- cv.glmnet(d$x, d$y, lambda = fit$lambda, standardize = standardize, intercept = intercept, thresh = 1e-14,
                   foldid = foldid)
  out("cvm_full", cvf$cvm)
  out("cvsd_full", cvf$cvsd)
  out("lambda_min_1se_full", c(cvf$lambda.min, cvf$lambda.1se))
}
case("standardized", 120, 12, TRUE, TRUE, 5)
case("raw_scale", 100, 10, FALSE, TRUE, 4)
case("no_intercept", 80, 8, TRUE, FALSE, 4)
case("wide", 30, 40, TRUE, TRUE, 3)
