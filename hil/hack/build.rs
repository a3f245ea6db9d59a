// cargo considers a package's build-dependencies only when it has a build script; the
// unified build-dependency features (proc-macro2, syn, serde for build scripts) need it.
fn main() {}
