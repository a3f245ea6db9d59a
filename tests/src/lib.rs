//! End-to-end tests of rigtwin live in `tests/tests/`; shared helpers live here.

pub mod generator;
pub mod servo_axis;

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::AtomicBool;

use rigtwin::protocol::Protocol;
use rigtwin::rehearse::{self, Options, Rehearsal, RehearseError};
use rigtwin::session::Session;
use rigtwin_diagnose::{DiagnoseOptions, Diagnosis, diagnose};

/// Rehearses `protocol` for one subject with `seed` into `out` on `jobs` threads,
/// silently and without a way to cancel, as the end-to-end tests need it.
/// `max_trials` cuts each schedule short (`None`: the whole protocol).
///
/// # Errors
/// The runtime's error.
pub fn rehearse_one(
    protocol: &Protocol,
    seed: u64,
    out: &Path,
    jobs: usize,
    max_trials: Option<usize>,
) -> Result<Rehearsal, RehearseError> {
    let options = Options {
        subjects: 1,
        seed,
        out_dir: out.to_path_buf(),
        jobs,
        max_trials,
    };
    rehearse::rehearse(protocol, &options, &|_| {}, &AtomicBool::new(false))
}

/// Generates a session hiding `effect` laid out by `design` into `out`
/// ([`generator::generate_design`]) and diagnoses it with the default options, as the
/// hidden-effect tests judge one.
///
/// # Errors
/// An unknown effect, the runtime's error, an unreadable session or the diagnosis's
/// error.
pub fn generate_and_diagnose(
    effect: &str,
    seed: u64,
    design: &generator::Design,
    out: &Path,
) -> Result<(generator::Generated, Diagnosis), Box<dyn std::error::Error + Send + Sync>> {
    let g = generator::generate_design(effect, seed, design, out)?;
    let s = Session::read(&g.dir)?;
    let d = diagnose(&s, &DiagnoseOptions::default())?.diagnosis;
    Ok((g, d))
}

/// Every file under `dir`, by `/`-separated path relative to it, with its bytes.
///
/// # Errors
/// The first I/O error met.
pub fn files(dir: &Path) -> std::io::Result<BTreeMap<String, Vec<u8>>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d)? {
            let p = e?.path();
            if p.is_dir() {
                stack.push(p);
            } else if let Ok(rel) = p.strip_prefix(dir) {
                let rel = rel.to_string_lossy().replace('\\', "/");
                out.insert(rel, std::fs::read(&p)?);
            }
        }
    }
    Ok(out)
}
