"""One frame end to end: detection, range planning, tiling, the predictors and the mixture families."""
