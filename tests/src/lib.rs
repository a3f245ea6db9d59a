//! End-to-end tests of rigtwin live in `tests/tests/`; shared helpers live here.

pub mod generator;
