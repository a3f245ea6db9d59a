//! Running `rigtwin` on hostile input as a person's shell would, and judging how it
//! ended: a clean exit (0), a clear refusal (1, or 2 for a bad command line), or a
//! failure of the program itself — a signal (SIGABRT from a failed allocation), a panic
//! (exit 101), or no end within the case's time (a hang). Shared by `hostile_inputs`
//! (the cases found by review, one test each) and `hostile_corpus` (generated cases).
#![allow(dead_code)]
// A child is polled with a short relative wait: that is what "give it N seconds" means.
#![allow(clippy::disallowed_methods)]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How a run ended.
#[derive(Debug)]
pub struct Ended {
    /// The exit code; `None` if a signal ended it or it was killed for time.
    pub code: Option<i32>,
    /// The signal that ended it, if one did.
    pub signal: Option<i32>,
    /// It did not end within its time and was killed.
    pub hung: bool,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
    /// Wall time, s.
    pub wall_s: f64,
}

impl Ended {
    /// The program itself failed: a signal, a panic or a hang.
    #[must_use]
    pub fn failed(&self) -> Option<String> {
        if self.hung {
            return Some(format!("hang (killed after {:.1} s)", self.wall_s));
        }
        if let Some(s) = self.signal {
            return Some(format!("signal {s} (abort is 6)"));
        }
        if self.code == Some(101) || self.stderr.contains("panicked") {
            return Some("panic".into());
        }
        match self.code {
            Some(0..=2) => None,
            other => Some(format!("exit {other:?}")),
        }
    }

    /// Ended with a refusal (exit 1 or 2).
    #[must_use]
    pub fn refused(&self) -> bool {
        matches!(self.code, Some(1 | 2))
    }
}

/// The binary under test.
#[must_use]
pub fn exe() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_rigtwin"))
}

/// Runs `rigtwin args` in `cwd` with at most `secs` seconds, stdout to `stdout` (a file
/// such as `/dev/full`) or captured.
pub fn run_in(cwd: &Path, args: &[&str], secs: f64, stdout: Option<&Path>) -> Ended {
    let mut cmd = Command::new(exe());
    cmd.args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .env("RUST_BACKTRACE", "0");
    match stdout {
        Some(p) => {
            let f = std::fs::OpenOptions::new().write(true).open(p).unwrap();
            cmd.stdout(f);
        }
        None => {
            cmd.stdout(Stdio::piped());
        }
    }
    let start = Instant::now();
    let mut child = cmd.spawn().unwrap();
    // Drain the pipes on threads so a chatty child cannot block on a full pipe.
    let out = child.stdout.take().map(|mut s| {
        std::thread::spawn(move || {
            let mut b = Vec::new();
            let _ = std::io::Read::read_to_end(&mut s, &mut b);
            b
        })
    });
    let err = child.stderr.take().map(|mut s| {
        std::thread::spawn(move || {
            let mut b = Vec::new();
            let _ = std::io::Read::read_to_end(&mut s, &mut b);
            b
        })
    });
    let limit = Duration::from_secs_f64(secs);
    let (status, hung) = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break (Some(status), false);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break (None, true);
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let wall_s = start.elapsed().as_secs_f64();
    let text = |h: Option<std::thread::JoinHandle<Vec<u8>>>| {
        h.map(|h| String::from_utf8_lossy(&h.join().unwrap()).into_owned())
            .unwrap_or_default()
    };
    let (stdout, stderr) = (text(out), text(err));
    use std::os::unix::process::ExitStatusExt as _;
    Ended {
        code: status.and_then(|s| s.code()),
        signal: status.and_then(|s| s.signal()),
        hung,
        stdout,
        stderr,
        wall_s,
    }
}

/// The shared recordings beside the checkout.
#[must_use]
pub fn shared(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/recordings")
        .join(name)
}

/// A copy of `example-none` with its first `trials` trials, in `dir`.
pub fn small_session(dir: &Path, trials: usize) -> PathBuf {
    let src = shared("example-none");
    let out = dir.join("session");
    std::fs::create_dir_all(out.join("trials")).unwrap();
    let manifest = std::fs::read_to_string(src.join("session.toml")).unwrap();
    // Keep the header and the first `trials` [[trial]] blocks.
    let mut blocks = manifest.split("[[trial]]");
    let mut text = blocks.next().unwrap().to_owned();
    for b in blocks.take(trials) {
        text.push_str("[[trial]]");
        text.push_str(b);
    }
    std::fs::write(out.join("session.toml"), text).unwrap();
    for k in 1..=trials {
        let name = format!("trials/{k:04}.csv");
        std::fs::copy(src.join(&name), out.join(&name)).unwrap();
    }
    out
}

/// Creates a FIFO at `path`.
pub fn mkfifo(path: &Path) {
    let status = Command::new("mkfifo").arg(path).status().unwrap();
    assert!(status.success(), "mkfifo {}", path.display());
}
