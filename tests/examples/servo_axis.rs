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
//! (default 40). Prints the axis's true parameters.

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
    if let Ok(d) = std::env::var("SERVO_DELAY_TICKS") {
        axis.delay_ticks = d.parse().map_err(|e| format!("SERVO_DELAY_TICKS: {e}"))?;
    }
    let log = run(&axis, moves, 0.1, seed);
    std::fs::create_dir_all(&out)?;
    std::fs::write(out.join("servo.csv"), log_csv(&log))?;
    write_session(&log, &axis, &out.join("session"))?;
    println!("{}", out.join("session").display());
    println!("{axis:#?}");
    Ok(())
}
