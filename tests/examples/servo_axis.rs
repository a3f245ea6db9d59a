//! Runs the emulated linear servo axis (`rigtwin_tests::servo_axis`) and writes what a
//! bench logger would: a continuous CSV log `servo.csv` (time, position and reference
//! in mm, drive command in V), and the same samples as a one-axis session `session/`:
//!
//! ```sh
//! cargo run --release -p rigtwin-tests --example servo_axis -- 7 /tmp/servo
//! rigtwin diagnose /tmp/servo/session
//! ```
//!
//! Arguments: seed, output folder (new or empty); optional third: number of moves
//! (default 40). Variants of the bench axis through the environment:
//! `SERVO_DELAY_TICKS`, `SERVO_COGGING_N`, `SERVO_STRIBECK_N`, `SERVO_KI`,
//! `SERVO_NOISE_N`, `SERVO_OFFSET_N`, `SERVO_COULOMB_N`, `SERVO_VISCOUS`,
//! `SERVO_MASS_KG`, `SERVO_ENCODER_M`, `SERVO_RATE_HZ`. Prints the axis's true parameters.

use rigtwin_tests::servo_axis::{ServoAxis, log_csv, run, write_session};

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: servo_axis <seed> <out> [moves]";
    let seed: u64 = args
        .first()
        .ok_or(usage)?
        .parse()
        .map_err(|e| format!("seed: {e}; {usage}"))?;
    let out = std::path::PathBuf::from(args.get(1).ok_or(usage)?);
    let moves: usize = match args.get(2) {
        Some(m) => m.parse().map_err(|e| format!("moves: {e}; {usage}"))?,
        None => 40,
    };
    let mut axis = ServoAxis::bench();
    // Variants of the bench axis for looking at the diagnosis by hand.
    let env = |k: &str| std::env::var(k).ok();
    let num = |k: &str, v: String| v.parse::<f64>().map_err(|e| format!("{k}: {e}"));
    if let Some(d) = env("SERVO_DELAY_TICKS") {
        axis.delay_ticks = d.parse().map_err(|e| format!("SERVO_DELAY_TICKS: {e}"))?;
    }
    for (k, field) in [
        ("SERVO_COGGING_N", &mut axis.cogging_n),
        ("SERVO_STRIBECK_N", &mut axis.stribeck_n),
        ("SERVO_KI", &mut axis.ki),
        ("SERVO_NOISE_N", &mut axis.noise_n),
        ("SERVO_OFFSET_N", &mut axis.offset_n),
        ("SERVO_COULOMB_N", &mut axis.coulomb_n),
        ("SERVO_VISCOUS", &mut axis.viscous_n_s_per_m),
        ("SERVO_MASS_KG", &mut axis.mass_kg),
        ("SERVO_ENCODER_M", &mut axis.encoder_m),
        ("SERVO_RATE_HZ", &mut axis.rate_hz),
    ] {
        if let Some(v) = env(k) {
            *field = num(k, v)?;
        }
    }
    let log = run(&axis, moves, 0.1, seed);
    std::fs::create_dir_all(&out)?;
    std::fs::write(out.join("servo.csv"), log_csv(&log))?;
    write_session(&log, &axis, &out.join("session"))?;
    println!("{}", out.join("session").display());
    println!("{axis:#?}");
    Ok(())
}
