//! rigtwin-world (under construction in its issue).
