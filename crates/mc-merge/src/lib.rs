//! Merges Monte Carlo shards into percentile estimates with bootstrap confidence intervals, the Rayleigh law and plots.
