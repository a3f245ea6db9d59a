//! rigtwin-arm (under construction in its issue).
