//! Nonlinear static equilibrium of pin-jointed trusses with tension-only cables, and the distortion angle of the paper.
