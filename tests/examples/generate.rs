//! Writes one generated session hiding a catalog effect, for looking at it by hand:
//!
//! ```sh
//! cargo run --release -p rigtwin-tests --example generate -- stretch-reflex 7 /tmp/gen
//! rigtwin diagnose /tmp/gen/<session>
//! ```
//!
//! Arguments: effect name (`none` or a catalog name), seed, output folder (new or
//! empty); optional fourth: trials (default 32). Prints the session folder and what it
//! hides.

use rigtwin_tests::generator::{EFFECTS, generate};

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [effect, seed, out, rest @ ..] = args.as_slice() else {
        return Err(
            format!("usage: generate <effect> <seed> <out> [trials]; effects {EFFECTS:?}").into(),
        );
    };
    let seed: u64 = seed.parse().map_err(|e| format!("seed {seed:?}: {e}"))?;
    let trials: usize = match rest.first() {
        Some(t) => t.parse().map_err(|e| format!("trials {t:?}: {e}"))?,
        None => 32,
    };
    let g = generate(effect, seed, trials, std::path::Path::new(out))?;
    println!("{}", g.dir.display());
    println!("hidden {} {:?}", g.hidden.effect, g.hidden.parameters);
    Ok(())
}
