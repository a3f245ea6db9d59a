//! The `rigtwin` command.
fn main() {
    println!("rigtwin {}", env!("CARGO_PKG_VERSION"));
}
