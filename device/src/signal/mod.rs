//! Signal processing for the estimators, checked against scipy on golden vectors.
