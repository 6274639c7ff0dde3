"""Studies: convergence of the estimators, and what accuracy costs in time."""
