//! Impedance estimators the rig runs: Börner involuntary impedance (000_*) and the
//! Piovesan windowed regression (001_*), with ellipse metrics.
