//! Writes one generated session hiding a catalog effect, for looking at it by hand:
//!
//! ```sh
//! cargo run --release -p rigtwin-tests --example generate -- stretch-reflex 7 /tmp/gen
//! cargo run --release -p rigtwin-tests --example generate -- stretch-reflex 2 /tmp/q --no-motor-noise
//! rigtwin diagnose /tmp/gen/<session>
//! ```
//!
//! Arguments: effect name (`none` or a catalog name), seed, output folder (new or
//! empty); optional fourth: trials (default 32). `--no-motor-noise` (anywhere) switches
//! the arm's motor noise off, keeping subject and effect. Prints the session folder and
//! what it hides.

use rigtwin_tests::generator::{EFFECTS, generate_with};

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let all: Vec<String> = std::env::args().skip(1).collect();
    let quiet = all.iter().any(|a| a == "--no-motor-noise");
    let args: Vec<&String> = all.iter().filter(|a| *a != "--no-motor-noise").collect();
    let usage = || {
        format!(
            "usage: generate <effect> <seed> <out> [trials] [--no-motor-noise]; effects {EFFECTS:?}"
        )
    };
    let [effect, seed, out, rest @ ..] = args.as_slice() else {
        return Err(usage().into());
    };
    if let Some(bad) = rest.get(1).or(rest.iter().find(|a| a.starts_with("--"))) {
        return Err(format!("unexpected argument {bad:?}; {}", usage()).into());
    }
    let seed: u64 = seed.parse().map_err(|e| format!("seed {seed:?}: {e}"))?;
    let trials: usize = match rest.first() {
        Some(t) => t.parse().map_err(|e| format!("trials {t:?}: {e}"))?,
        None => 32,
    };
    let g = generate_with(
        effect,
        seed,
        trials,
        std::path::Path::new(out.as_str()),
        !quiet,
    )?;
    println!("{}", g.dir.display());
    println!("hidden {} {:?}", g.hidden.effect, g.hidden.parameters);
    Ok(())
}
