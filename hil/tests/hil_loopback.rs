//! Hardware in the loop on loopback, in real time: `rigtwin plant serve` and
//! `rigtwin controller` as two processes talking the wire protocol over UDP, and the
//! standard-library Python client of `hil/examples/` holding the served handle.
//!
//! These run on a shared 2-core machine, where the scheduler stalls a process for up to
//! 10 ms now and then (README, "Hardware in the loop"). With the rig's 1 ms watchdogs a
//! stall trips the controller, which is right on a rig and says nothing about the loop,
//! so these tests run the shipped reach protocol with the watchdogs and the controller's
//! clock-skip allowance at 40 ticks (10 ms) on both ends: what they assert is that the
//! loop works (sessions valid and complete, timing recorded, the handle following the
//! admittance's reference, the PD law holding the handle against the subject, the
//! e-stop chain closing). The watchdogs at exactly N ticks are tested in lock step
//! (`hil/wire/tests/lockstep.rs`, `tests/tests/wire_equivalence.rs`). The tests take a
//! lock so that only one pair of processes runs at a time.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::io::{BufRead as _, BufReader};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};

use rigtwin::session::Session;

const BIN: &str = env!("CARGO_BIN_EXE_rigtwin");

/// One loop at a time: two real-time processes per test on a 2-core machine.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The shipped reach protocol with 10 ms allowances (module docs), written into `dir`.
fn protocol(dir: &Path) -> String {
    let text = include_str!("../protocols/reach-perturb.toml");
    let patched = text.replace("max_consecutive_misses = 4", "max_consecutive_misses = 40");
    assert_ne!(
        text, patched,
        "the shipped protocol sets max_consecutive_misses = 4"
    );
    let path = dir.join("reach-perturb.toml");
    std::fs::write(&path, patched).unwrap();
    path.to_str().unwrap().to_owned()
}

/// The watchdogs of both ends at 40 ticks.
const LOOSE: [&str; 2] = ["--stale-ticks", "40"];

/// Starts `plant serve` on a free loopback port; returns the child and the address it
/// printed.
fn serve(out: &Path, extra: &[&str]) -> (Child, String) {
    let proto = protocol(out.parent().unwrap());
    let mut child = Command::new(BIN)
        .args(["plant", "serve", &proto, "--listen", "127.0.0.1:0"])
        .args(LOOSE)
        .args(["--seed", "42", "--max-trials", "1", "--idle-timeout-s", "2"])
        .arg("--out")
        .arg(out)
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    let addr = first
        .strip_prefix("listening on ")
        .unwrap_or_else(|| panic!("first line of plant serve: {first:?}"))
        .to_owned();
    // Keep draining stderr so the server never blocks on a full pipe.
    std::thread::spawn(move || for _ in lines {});
    (child, addr)
}

/// Runs `rigtwin controller` on `protocol` (seed 42, one trial, 10 ms allowances)
/// against the plant at `addr`, into `out`; returns its standard output.
fn controller(protocol: &str, addr: &str, out: &Path) -> String {
    let ctl = Command::new(BIN)
        .args(["controller", protocol, "--seed", "42", "--max-trials", "1"])
        .args(LOOSE)
        .args(["--max-gap", "40", "--rig", &format!("udp://{addr}")])
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    succeeded(ctl, "controller")
}

/// The standard output of a process that must have succeeded (`what` names it).
fn succeeded(out: Output, what: &str) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{what} failed: {}\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

fn finish(child: Child, what: &str) -> String {
    succeeded(child.wait_with_output().unwrap(), what)
}

fn column<'a>(t: &'a rigtwin::session::Trial, name: &str) -> &'a [f64] {
    &t.extra
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("column {name}"))
        .values
}

#[test]
fn plant_serve_and_controller_run_a_reach_over_udp() {
    let _one = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let tmp = tempfile::tempdir().unwrap();
    let plant_dir = tmp.path().join("plant");
    let ctl_dir = tmp.path().join("controller");
    let (plant, addr) = serve(&plant_dir, &[]);
    let protocol_path = protocol(tmp.path());
    let ctl_out = controller(&protocol_path, &addr, &ctl_dir);
    let plant_out = finish(plant, "plant serve");
    assert!(ctl_out.contains("Real-time timing"), "{ctl_out}");
    assert!(plant_out.contains("1 trials recorded"), "{plant_out}");

    // The controller's session: one whole trial at the recording rate, with its clock.
    let protocol = rigtwin::protocol::Protocol::builtin("reach-perturb").unwrap();
    let n_ticks = rigtwin::rehearse::trial::trial_ticks(&protocol);
    let div = rigtwin::rehearse::TICK_HZ / u64::from(protocol.recording.rate_hz);
    let rows = (n_ticks / div) as usize;
    let s = Session::read(&ctl_dir).unwrap();
    let timing = s.manifest.timing.expect("the controller's [timing]");
    assert!(
        timing.ticks + timing.missed_deadlines >= n_ticks,
        "{timing:?}"
    );
    assert!(timing.wake_latency.p50_us <= timing.wake_latency.max_us);
    let (_, t) = s.trial(1).unwrap();
    assert_eq!(t.t_s.len(), rows);
    // Nothing of the plant's truth crossed the wire.
    assert!(t.extra.iter().all(|c| c.name != "true_x_m"));

    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(ctl_dir.join("controller.json")).unwrap())
            .unwrap();
    let t1 = &report["trials"][0];
    let div = div as usize;
    let row_of = |key: &str| t1[key].as_u64().map_or(rows, |k| k as usize / div);
    // Until the first missed deadline (or a trip) of the controller, and the plant's
    // first stall, nothing was held longer than a tick: what follows holds there
    // whatever the scheduler did later. (With 10 ms allowances a long stall can
    // hold a command long enough to throw the handle and trip the velocity limit, as it
    // would on a rig: that is the 1 ms allowance's reason.)
    // The plant's side of the same condition: its first stall (2 or more ticks without
    // a fresh command: late datagrams or a late wake-up of the plant), from its output;
    // a row of margin for the two ends' trial clocks. Single late datagrams hold a
    // command for a tick; they are common on a loaded machine and inside the bound.
    let stall = plant_out
        .lines()
        .find_map(|l| {
            let rest = l.strip_prefix("trial 1: first stall (")?;
            rest.split(" at tick ")
                .nth(1)?
                .split_whitespace()
                .next()?
                .parse::<usize>()
                .ok()
        })
        .map_or(rows, |k| (k / div).saturating_sub(1));
    let exact = row_of("first_miss_tick")
        .min(row_of("trip_tick"))
        .min(stall);

    // The handle follows the admittance: the rig's position loop tracks the reference
    // through a round trip of one tick over loopback. Measured: 0.03-0.6 mm at most over
    // whole reaches; 1 mm is a tenth of what an open loop would show.
    let (y, r) = (&t.y_m, t.ref_y_m.as_ref().unwrap());
    let worst = y[..exact]
        .iter()
        .zip(&r[..exact])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-3,
        "max |y - ref_y| = {worst} m over the first {exact} rows"
    );

    // Equivalence with lock step: until the first missed deadline or stall the trial
    // over UDP is the lock-step trial of the same protocol and seed but for the wire's
    // one tick of delay (the plant applies the command answering frame n at n + 1) and
    // single late datagrams. Measured on a quiet machine over a whole reach without a
    // missed deadline: max |Δy| 0.06 mm, median 5 µm (the commands differ by 1.5 N
    // median, the hand force by 0.4 N); up to the plant's first stall on a loaded one
    // (rows 97–640 of 3500 over six runs) 1–10 µm; 0.2 mm would be exceeded by another
    // trial, seed or noise stream, and was by runs of 2–3 held ticks (0.23 mm).
    let lock_dir = tmp.path().join("lock");
    let lock = Command::new(BIN)
        .args([
            "rehearse",
            &protocol_path,
            "--seed",
            "42",
            "--max-trials",
            "1",
        ])
        .args(["--jobs", "1", "--out"])
        .arg(&lock_dir)
        .output()
        .unwrap();
    succeeded(lock, "rehearse");
    let l = Session::read(lock_dir.join("S01")).unwrap();
    let (_, lt) = l.trial(1).unwrap();
    let dev = lt.y_m[..exact]
        .iter()
        .zip(&y[..exact])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "before the first missed deadline or stall (row {exact} of {rows}): max |y_udp - y_lock| = {dev:e} m"
    );
    assert!(
        dev < 2e-4,
        "max |y_udp - y_lock| = {dev} m over the first {exact} rows"
    );

    // The plant's session: the true state of the same trial, with the applied force.
    let p = Session::read(&plant_dir).unwrap();
    assert!(p.manifest.timing.is_some());
    let (_, pt) = p.trial(1).unwrap();
    assert_eq!(pt.t_s.len(), rows);
    let hand = column(pt, "hand_fy_n");
    assert!(hand.iter().any(|f| f.abs() > 0.5), "the subject pushed");
}

#[test]
fn the_python_pd_client_holds_the_served_handle() {
    let _one = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let tmp = tempfile::tempdir().unwrap();
    let plant_dir = tmp.path().join("plant");
    let (plant, addr) = serve(&plant_dir, &[]);
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/pd_client.py");
    let py = Command::new("python3")
        .args([script, "--plant", &addr, "--seconds", "2"])
        .output()
        .unwrap();
    let py_out = succeeded(py, "pd_client");
    let plant_out = finish(plant, "plant serve");
    let number = |key: &str| -> f64 {
        py_out
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{key} in {py_out}"))
    };
    // 2 s at 4 kHz are 8000 frames; a Python loop on a loaded machine answers fewer, but
    // a client that answers at all answers thousands.
    assert!(number("frames ") > 1000.0, "{py_out}");
    let dev_mm = py_out
        .lines()
        .find_map(|l| l.split("largest deviation ").nth(1))
        .and_then(|v| v.trim_end_matches(" mm").parse::<f64>().ok())
        .unwrap();
    // The subject reaches 250 mm toward its goal; against 10 000 N/m its push of up to
    // about 70 N moves the handle some millimetres (measured: 7.3 mm over 3 s). 25 mm is
    // a tenth of the reach: more would mean the PD law did not hold (the watchdog
    // zeroing it, or no force).
    assert!(dev_mm < 25.0, "{py_out}");
    // The plant's own record agrees that the handle stayed near where it started while
    // the client held it, and that the motors pushed back.
    let p = Session::read(&plant_dir).unwrap();
    let (_, t) = p.trial(1).unwrap();
    let true_y = column(t, "true_y_m");
    let cmd = t.cmd_fy_n.as_ref().unwrap();
    assert!(cmd.iter().any(|f| f.abs() > 1.0), "{plant_out}");
    let held = true_y
        .iter()
        .take(t.t_s.len() / 2)
        .fold(0.0_f64, |m, v| m.max((v - true_y[0]).abs()));
    assert!(
        held < 0.025,
        "true y moved {held} m in the first half: {plant_out}"
    );
}

#[test]
fn an_estop_at_the_plant_trips_the_controller_over_udp() {
    let _one = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let tmp = tempfile::tempdir().unwrap();
    let (plant, addr) = serve(&tmp.path().join("plant"), &["--estop-at-s", "0.3"]);
    let ctl_out = controller(&protocol(tmp.path()), &addr, &tmp.path().join("controller"));
    let plant_out = finish(plant, "plant serve");
    // The controller latched on the e-stop (unless a stall tripped it before 0.3 s).
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(tmp.path().join("controller").join("controller.json")).unwrap(),
    )
    .unwrap();
    let trip = report["trials"][0]["trip"]
        .as_str()
        .unwrap_or_else(|| panic!("no trip: {ctl_out}"));
    if trip == "EStop" {
        // Press → frame out → controller trips at its next read → fault command back:
        // on loopback a few ticks; 400 ticks (100 ms) is a human's reaction time, the
        // bound past which an e-stop chain is broken whatever the scheduler does.
        let line = plant_out
            .lines()
            .find(|l| l.starts_with("e-stop to zero force"))
            .unwrap_or_else(|| panic!("no e-stop latency: {plant_out}"));
        let max_ticks: u64 = line
            .split("max ")
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .unwrap();
        assert!((1..=400).contains(&max_ticks), "{line}");
    } else {
        eprintln!("a stall tripped the controller before the e-stop: {trip}");
    }
}
