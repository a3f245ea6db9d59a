//! `rigtwin import`: a lab's measured log (MATLAB `.mat`, level 5 or v7.3; CSV/TSV)
//! and a map file in, a session out (`rigtwin-import`); `--inspect` lists what a log
//! holds, so that a person can write the map.

use std::path::PathBuf;

use anyhow::Context as _;

/// Turn measured logs into a session: MATLAB `.mat` files, level 5 or v7.3 (HDF5),
/// structs of arrays included, and continuous CSV/TSV logs, through a TOML map file
/// that says which variable or column is which channel, its scale into SI units, the
/// log's clock, how to cut trials (whole log, marker channel, table of
/// onsets, movement threshold) and what the device is. The map's reference, with a full
/// example, is `cargo doc -p rigtwin-import --open` (the crate's front page) and the
/// README's "Importing measured data". Every error names the file, the line or
/// variable, and the map key; nothing is written unless everything checks.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin import --inspect recordings/example-servo-axis/servo.mat
  rigtwin import recordings/example-servo-axis/servo.mat \\
      --map recordings/example-servo-axis/map.toml --out /tmp/servo
  rigtwin import day1.csv day2.csv --map rig.toml --out sessions/S07
  rigtwin diagnose /tmp/servo")]
pub struct Args {
    /// Log files, in order (trials are numbered across them).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,

    /// The map file (TOML). Required unless --inspect.
    #[arg(long, required_unless_present = "inspect")]
    pub map: Option<PathBuf>,

    /// The session folder to write (new, or empty). Required unless --inspect.
    #[arg(long, required_unless_present = "inspect")]
    pub out: Option<PathBuf>,

    /// List what each file holds (names, shapes, types, rates it can infer) and stop.
    #[arg(long, conflicts_with_all = ["map", "out"])]
    pub inspect: bool,
}

/// Runs `rigtwin import`.
///
/// # Errors
/// A log or map that cannot be read or used, or a session that cannot be written,
/// naming the file, the line or variable, and the map key.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.inspect {
        for f in &args.files {
            let inv = rigtwin_import::inspect(f)
                .with_context(|| format!("inspecting {}", f.display()))?;
            out!("{inv}");
        }
        return Ok(());
    }
    let (Some(map), Some(out)) = (&args.map, &args.out) else {
        anyhow::bail!("--map and --out are required unless --inspect");
    };
    let imported = rigtwin_import::import(&args.files, map, out)
        .with_context(|| format!("importing into {}", out.display()))?;
    out!(
        "{imported}\nnext: rigtwin inspect {0}\n      rigtwin diagnose {0}\n",
        out.display()
    );
    Ok(())
}
