//! No code: this package exists for its dependency lines. `hil` and `tests` depend on it,
//! so every build that includes them — `cargo run -- rehearse …` as much as
//! `cargo test --workspace` with all its dev-dependencies — resolves the same features
//! for the crates listed in its `Cargo.toml`, and one build serves both commands.
//! `device`, `arm`, `world`, `hil/session` and `hil/wire` do not depend on it, so a rig-side build of
//! the controller alone stays small. cargo-hakari writes the list; see `Cargo.toml`.
