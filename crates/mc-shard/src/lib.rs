//! Reproducible seeded shards of a truss Monte Carlo job, written as JSON Lines.
