//! Samples a logger lost while it kept its clock, found from the position and put
//! back before the balances are fitted.
//!
//! A logger that numbers its rows itself (`t_s = row / rate_hz`) and drops a frame, a
//! stream's lost datagram, a buffer overrun, writes every later row one period early:
//! every channel slips by one sample at once, and the format's uniform clock cannot
//! show it. The balances differentiate the position twice, so the slip's jump of
//! `v·dt` becomes an acceleration doublet of `±v/dt`: seven slips at peak speed in a
//! session of 32 trials made the faulty-unit rule set aside two good trials and cut a
//! delay's held-out gain from 0.34 to 0.22 (`hil/docs/notes/2026-12-06-glitches.md`).
//!
//! **The signature.** A run of `n` samples lost between rows `i − 1` and `i` stretches
//! the position's step there: with `d_k = x_k − x_{k−1}`, `d_i ≈ (n + 1) v dt` while its
//! neighbours carry `v dt`, so `d` has a lone spike `n` times the size of its
//! neighbours' mean. A slip is a row where, in the faster of the two position channels,
//! `d` has a lone spike (the [`super::glitch`] rule on `d`: above ten robust sigmas and
//! the 20 µm floor, its neighbours' departures opposite at 0.25–0.75 of it, the samples
//! two away under a quarter) of a whole number `n` ≤ [`MAX_LOST`] of times the
//! neighbours' mean step, within [`RATIO_TOLERANCE`], and the other channel's step there
//! is its neighbours' mean times `n + 1` too, within that tolerance of the faster one's
//! mean. A glitch is not a slip: it leaves `d` a dipole (`+s`, then `−s`), and a stale
//! frame a dipole the other way (`0`, then `2 v dt`). A slip below 20 µm (`v < 20 mm/s`
//! at 1 kHz, 80 mm/s at 4 kHz) is left: its doublet moves no fit.
//!
//! **The repair.** The lost samples are put back in every column at their times, by the
//! cubic through the two recorded samples on either side (true times `−1, 0` and
//! `n + 1, n + 2` periods from the row before the gap; for one lost sample the weights
//! `−1/6, 2/3, 2/3, −1/6`), and the time column is renumbered. The files are never
//! changed; [`Slip`] lists each run with its trial's file, the recorded row after which
//! it was lost and how many samples it held. Rows in [`super::glitch::Glitch`] are the
//! file's, and found before the repair. A stream that loses a datagram now and then
//! loses two or three in a row as often as its loss comes in bursts: two lost samples
//! at peak speed in 8 of 32 trials took a 1.575 ms delay to 1.825 ms and its held-out
//! gain from 0.34 to 0.06 (`hil/docs/notes/2026-12-06-lost-runs.md`).
//!
//! **A frame written twice.** A logger whose clock runs a little slower than the rig's
//! loses a frame now and then; one whose clock runs a little faster writes a frame
//! twice, and every later row is one period late. Such a row repeats the row before
//! exactly in every measured channel (position, force, drive velocity), which a rig
//! read at every row never does while it moves: its force sensor's noise changes the
//! force at every row. A repeated frame is a row that repeats the row before in every
//! measured channel while the faster position channel steps by at least 20 µm into
//! the row before and out of the run of such rows (up to [`MAX_LOST`] of them), the
//! same way. It is taken out of every column
//! before the lost samples are looked for, and the time is renumbered; [`Repeat`] lists
//! each with its file's row. A logger that wrote the previous frame in place of a lost
//! one (a stale frame) is, where the handle moves, bridged by [`super::glitch`] first:
//! its position leaves the line between its neighbours. One the glitch rule leaves
//! (below its threshold) is taken out here, which leaves a lost sample, put back next:
//! the repair of the two faults one after the other. Seven repeated
//! frames at peak speed in a session of 32 trials did what seven lost ones did: two
//! good trials set aside and a 1.6 ms delay's held-out gain from 0.34 to 0.22
//! (`hil/docs/notes/2026-12-06-held-samples.md`). A trial with a held channel
//! ([`super::hold`]) repeats by design and is not searched, nor is a trial without a
//! force sensor (constant force columns: nothing tells a repeat from a stalled
//! encoder), nor a frame repeated at rest, which moves no fit.
//!
//! **A position sensor faster than the log.** An encoder interface on its own clock a
//! little faster than the logger's (1001 or 1010 Hz into 1 kHz; two crystals, or a
//! stream at its own rate) is read at each row for its latest reading: one reading in
//! `d + 1` is never shown, and the rest are up to a row old, each `1/(d + 1)` of a row
//! older than the one before until the next skip. The position steps twice its
//! neighbours' mean at a skip, as at a lost frame, but nothing else skipped: the
//! controller's reference (`ref_x_m`, `ref_y_m`), computed at every tick on the log's
//! clock, steps on as before, where a lost frame stretches its step too (at the rows
//! found: 1.00 and 2.00 times its neighbours' mean). Put back in every column as lost,
//! such skips left the force a row late after each: 1010 Hz took the delay's seed 1000
//! to 2.075 ms and a gain of 0.123 (clean 1.575 ms, 0.337), and seed 1001's out of the
//! findings. Left as recorded, worse (1001 Hz: gain 0.112). So a single lost sample
//! where the reference moves by at least 20 µm a row and steps within
//! [`RATIO_TOLERANCE`] of its neighbours' mean is a skip ([`Skip`]), and the position
//! channels of its trial are put on the log's rows: each row's reading at its time from
//! the skips around it (`d` from the next skip, or the session's median spacing of
//! skips), and each row's value the cubic through the four readings around it at their
//! times. A log without the reference columns cannot show a skip, and its skips are put
//! back as lost samples, as before. A clock within about 100 ppm of the log's skips at
//! most once a trial: the readings either side of it are put a row apart in age, and
//! the age's slow drift within the trial, unseen, is left
//! (`hil/docs/notes/2026-12-07-one-sensor-two-channels.md`).
//!
//! **A lone spike in a position's step that is neither** (not a whole number of the
//! neighbours' mean, or the other channel not stretched alike) is an encoder's count
//! jump, levelled in that channel before the rest is mended ([`super::jump`]).

use rigtwin_session::{Session, Trial};
use serde::Serialize;

use super::glitch;
use super::hold::Readings;
use super::jump::{self, Jump};

/// The longest run of lost (or repeated) samples searched, the longest run the glitch
/// rule bridges ([`super::glitch::MAX_RUN`]): a longer gap is a trial the logger broke,
/// which the faulty-unit rule sets aside.
pub const MAX_LOST: usize = 3;
/// How far the extra step over the neighbours' mean step may be from a whole number of
/// lost samples, in units of that mean: the path's velocity changing over the gap moves
/// it by its curvature only (a velocity linear in time leaves the sum of the gap's
/// steps at `n + 1` times the neighbours' mean exactly), and the noise little above the
/// 20 µm floor.
pub const RATIO_TOLERANCE: f64 = 0.25;

/// A sample lost by the logger, put back before the fits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Slip {
    /// The trial's file, as the manifest names it.
    pub file: String,
    /// The recorded row after which the sample was lost (0 for the first after the
    /// header).
    pub after_row: usize,
    /// That row's time in its trial as recorded, s.
    pub t_s: f64,
    /// How many samples in a row were lost there.
    pub samples: usize,
    /// The position's extra step there (the faster channel's), m.
    pub step_m: f64,
}

/// A reading the position sensor skipped: its clock runs faster than the log's, and the
/// controller's reference (on the log's clock) stepped on as before while the
/// position stepped twice (module docs, "A position sensor faster than the log").
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Skip {
    /// The trial's file, as the manifest names it.
    pub file: String,
    /// The recorded row that shows the reading after the skipped one (0 for the first
    /// after the header).
    pub row: usize,
    /// That row's time in its trial as recorded, s.
    pub t_s: f64,
}

/// A frame the logger wrote twice, taken out before the fits.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Repeat {
    /// The trial's file, as the manifest names it.
    pub file: String,
    /// The recorded row that repeats the one before it (0 for the first after the
    /// header).
    pub row: usize,
    /// That row's time in its trial as recorded, s.
    pub t_s: f64,
    /// The faster position channel's mean step into the row before and out of the
    /// row, m.
    pub step_m: f64,
}

/// The rows of `trial` that repeat the row before them in every measured channel, in
/// runs of up to [`MAX_LOST`], while the faster position channel steps by at least
/// [`glitch::POSITION_FLOOR_M`] into the row each run repeats and out of the run's last
/// row, the same way (module docs), each with that mean step.
#[must_use]
pub fn find_repeats(trial: &Trial) -> Vec<(usize, f64)> {
    let varies = |c: &[f64]| c.iter().any(|v| *v != c[0]);
    // Without a force sensor (its columns constant, as an imported servo axis logs
    // them) a repeat has nothing to be told apart by.
    if !varies(&trial.fx_n) && !varies(&trial.fy_n) {
        return Vec::new();
    }
    let columns: Vec<&[f64]> = glitch::SEARCHED
        .iter()
        .filter_map(|(channel, _)| trial.column(channel))
        .collect();
    let (x, y) = (&trial.x_m, &trial.y_m);
    let n = x.len().min(y.len());
    let repeats = |k: usize, of: usize| columns.iter().all(|c| c[k] == c[of]);
    let mut rows = Vec::new();
    let mut k = 2;
    while k + 1 < n {
        if !repeats(k, k - 1) {
            k += 1;
            continue;
        }
        // The run k..=last repeats row k − 1.
        let mut last = k;
        while last + 2 < n && repeats(last + 1, k - 1) {
            last += 1;
        }
        let run = last + 1 - k;
        let steps = |p: &[f64]| (p[k - 1] - p[k - 2], p[last + 1] - p[last]);
        let (ax, bx) = steps(x);
        let (ay, by) = steps(y);
        let (a, b) = if (ax + bx).abs() >= (ay + by).abs() {
            (ax, bx)
        } else {
            (ay, by)
        };
        if run <= MAX_LOST && glitch::moves_through(a, b) {
            rows.extend((k..=last).map(|r| (r, 0.5 * (a + b).abs())));
        }
        k = last + 1;
    }
    rows
}

/// The recorded rows `i` of a trial such that a run of samples was lost between
/// `i − 1` and `i`, with the run's length and the extra step (module docs).
#[must_use]
pub fn find(x: &[f64], y: &[f64]) -> Vec<(usize, usize, f64)> {
    let n = x.len().min(y.len());
    lost_among(x, y, &[jump::spikes(&x[..n]), jump::spikes(&y[..n])])
}

/// [`find`] on the lone spikes of each channel's step already found (`spikes`, of `x`
/// then `y`, from [`jump::spikes`] on their first `min(len)` samples).
fn lost_among(x: &[f64], y: &[f64], spikes: &[Vec<(usize, f64)>; 2]) -> Vec<(usize, usize, f64)> {
    let n = x.len().min(y.len());
    if n < 8 {
        return Vec::new();
    }
    let step = |p: &[f64]| -> Vec<f64> { p[..n].windows(2).map(|w| w[1] - w[0]).collect() };
    let (dx, dy) = (step(x), step(y));
    // d[k] is the step into row k + 1; a lone spike in it leads into row k + 1.
    let mut rows: Vec<(usize, usize, f64)> = Vec::new();
    for (fast, slow, spiked) in [(&dx, &dy, &spikes[0]), (&dy, &dx, &spikes[1])] {
        for k in spiked.iter().map(|&(row, _)| row - 1) {
            let mean = |d: &[f64]| 0.5 * (d[k - 1] + d[k + 1]);
            let (mf, ms) = (mean(fast), mean(slow));
            if mf.abs() < ms.abs() {
                continue;
            }
            let extra = fast[k] - mf;
            let ratio = extra / mf;
            let lost = ratio.round();
            let whole =
                lost >= 1.0 && lost <= MAX_LOST as f64 && (ratio - lost).abs() < RATIO_TOLERANCE;
            let other = (slow[k] - (lost + 1.0) * ms).abs() < RATIO_TOLERANCE * mf.abs();
            if whole && other && !rows.iter().any(|r| r.0 == k + 1) {
                rows.push((k + 1, lost as usize, extra.abs()));
            }
        }
    }
    rows.sort_by_key(|r| r.0);
    rows
}

/// Whether the controller's reference position (`ref_x_m`, `ref_y_m`, where logged)
/// steps into row `i` as its neighbours do, within [`RATIO_TOLERANCE`], where it moves
/// by at least [`glitch::POSITION_FLOOR_M`] a row: the logger then lost no frame there,
/// and a position that steps twice its neighbours' mean skipped a reading of its own.
/// The reference is what the controller computed at each tick, on the log's clock; a
/// lost frame stretches its step as it does the position's.
fn reference_kept(trial: &Trial, i: usize) -> bool {
    [&trial.ref_x_m, &trial.ref_y_m]
        .into_iter()
        .flatten()
        .filter(|r| i >= 2 && i + 1 < r.len())
        .map(|r| {
            let mean = 0.5 * ((r[i - 1] - r[i - 2]) + (r[i + 1] - r[i]));
            (mean, (r[i] - r[i - 1]) / mean)
        })
        .filter(|(mean, _)| mean.abs() >= glitch::POSITION_FLOOR_M)
        .max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()))
        .is_some_and(|(_, ratio)| (ratio - 1.0).abs() < RATIO_TOLERANCE)
}

/// The values of the `lost` samples lost between `v[i − 1]` and `v[i]`: the cubic
/// through rows `i − 2 … i + 1` at their true times `−1, 0, lost + 1, lost + 2`, at
/// times `1 … lost` ([`glitch::gap_cubic`]; module docs). [`find`] gives rows
/// `2 ≤ i ≤ len − 2` only (its spikes in the step have both neighbours).
fn lost_values(v: &[f64], i: usize, lost: usize) -> impl Iterator<Item = f64> {
    glitch::gap_cubic([v[i - 2], v[i - 1]], [v[i], v[i + 1]], lost)
}

/// `trial` with the samples of each run `(row, lost)` of `runs` (ascending rows) put
/// back before its recorded row, and its time renumbered at `period_s`.
fn repaired(trial: &Trial, runs: &[(usize, usize)], period_s: f64) -> Trial {
    let fill = |v: &[f64]| -> Vec<f64> {
        let lost: usize = runs.iter().map(|r| r.1).sum();
        let mut out = Vec::with_capacity(v.len() + lost);
        let mut next = runs.iter().peekable();
        for (k, &value) in v.iter().enumerate() {
            if let Some(&&(_, n)) = next.peek().filter(|r| r.0 == k) {
                out.extend(lost_values(v, k, n));
                next.next();
            }
            out.push(value);
        }
        out
    };
    each_column(trial, fill, period_s)
}

/// Every column of `trial` with `f` applied, the time renumbered at `period_s`.
fn each_column(trial: &Trial, f: impl Fn(&[f64]) -> Vec<f64>, period_s: f64) -> Trial {
    let f_opt = |v: &Option<Vec<f64>>| v.as_deref().map(&f);
    let mut t = Trial {
        t_s: Vec::new(),
        x_m: f(&trial.x_m),
        y_m: f(&trial.y_m),
        fx_n: f(&trial.fx_n),
        fy_n: f(&trial.fy_n),
        pert_fx_n: f(&trial.pert_fx_n),
        pert_fy_n: f(&trial.pert_fy_n),
        vx_m_per_s: f_opt(&trial.vx_m_per_s),
        vy_m_per_s: f_opt(&trial.vy_m_per_s),
        ref_x_m: f_opt(&trial.ref_x_m),
        ref_y_m: f_opt(&trial.ref_y_m),
        cmd_fx_n: f_opt(&trial.cmd_fx_n),
        cmd_fy_n: f_opt(&trial.cmd_fy_n),
        extra: trial
            .extra
            .iter()
            .map(|c| rigtwin_session::Column {
                name: c.name.clone(),
                values: f(&c.values),
            })
            .collect(),
    };
    t.t_s = (0..t.x_m.len()).map(|k| k as f64 * period_s).collect();
    t
}

/// `trial` without the rows `rows` (ascending), its time renumbered at `period_s`.
fn without(trial: &Trial, rows: &[usize], period_s: f64) -> Trial {
    let drop = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .enumerate()
            .filter(|(k, _)| rows.binary_search(k).is_err())
            .map(|(_, &x)| x)
            .collect()
    };
    each_column(trial, drop, period_s)
}

/// The file's row of row `row` of a trial from which the file's rows `removed`
/// (ascending) were taken out.
fn file_row(removed: &[usize], row: usize) -> usize {
    removed
        .iter()
        .fold(row, |r, &gone| if gone <= r { r + 1 } else { r })
}

/// One trial's finds: its repeated frames (the file's rows, steps); and on the rows of
/// the trial with its repeats taken out (`work`, `None` when it has none; `removed`,
/// the file's rows taken out), its lost runs (the rows after them, lengths, steps), its
/// position's skipped readings (rows) and its encoder's jumps (channel, row, step).
struct Found {
    twice: Vec<(usize, f64)>,
    lost: Vec<(usize, usize, f64)>,
    skips: Vec<usize>,
    jumps: Vec<(&'static str, usize, f64)>,
    work: Option<Trial>,
    removed: Vec<usize>,
}

impl Found {
    /// Its lost runs with the file's row after which each was lost, its length and step.
    fn lost_in_file(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        self.lost
            .iter()
            .map(|&(row, n, step)| (file_row(&self.removed, row - 1), n, step))
    }
}

/// What [`repair`] finds in one trial (module docs): repeated frames when
/// `search_repeats`, then lost runs, among single lost samples those the controller's
/// reference disowns ([`reference_kept`]): a position sensor's skipped readings, and the
/// lone spikes in a position's step that are neither: its encoder's jumps
/// ([`super::jump`]).
fn look(trial: &Trial, search_repeats: bool, period_s: f64) -> Found {
    let twice = if search_repeats {
        find_repeats(trial)
    } else {
        Vec::new()
    };
    let removed: Vec<usize> = twice.iter().map(|r| r.0).collect();
    let work = (!removed.is_empty()).then(|| without(trial, &removed, period_s));
    let on = work.as_ref().unwrap_or(trial);
    // Every lone spike in a position's step is found once: lost samples, skipped
    // readings and jumps are what each of them is.
    let n = on.x_m.len().min(on.y_m.len());
    let spikes = [jump::spikes(&on.x_m[..n]), jump::spikes(&on.y_m[..n])];
    let (skips, lost): (Vec<_>, Vec<_>) = lost_among(&on.x_m, &on.y_m, &spikes)
        .into_iter()
        .partition(|&(row, n, _)| n == 1 && reference_kept(on, row));
    let claimed = |row: usize| lost.iter().chain(&skips).any(|r| r.0 == row);
    let mut jumps: Vec<(&'static str, usize, f64)> = ["x_m", "y_m"]
        .into_iter()
        .zip(spikes)
        .flat_map(|(channel, spiked)| {
            spiked
                .into_iter()
                .filter(|&(row, _)| !claimed(row))
                .map(move |(row, step)| (channel, row, step))
        })
        .collect();
    jumps.sort_by_key(|j| j.1);
    Found {
        twice,
        lost,
        skips: skips.into_iter().map(|r| r.0).collect(),
        jumps,
        work,
        removed,
    }
}

/// What [`repair`] found and mended, each list in trial and row order, with the file's
/// rows.
#[derive(Debug, Default)]
pub struct Repairs {
    /// The runs of lost samples put back.
    pub slips: Vec<Slip>,
    /// The repeated frames taken out.
    pub repeats: Vec<Repeat>,
    /// The position sensor's skipped readings, its position retimed.
    pub skips: Vec<Skip>,
    /// The position encoder's jumps, levelled ([`super::jump`]).
    pub jumps: Vec<Jump>,
}

/// The session with every repeated frame taken out, every lost sample put back, the
/// position of a sensor that skipped readings put at the log's rows and every encoder
/// jump levelled (module docs), and what was found; `None` in place of the session when
/// nothing was (the caller keeps its own). Trials with a held channel (`held`, from
/// [`super::hold::find`]) are not searched for repeats.
#[must_use]
pub fn repair(session: &Session, held: &Readings) -> (Option<Session>, Repairs) {
    let period_s = 1.0 / session.manifest.rate_hz;
    let found: Vec<Found> = session
        .trials
        .iter()
        .enumerate()
        .map(|(index, trial)| look(trial, !held.any_held(index), period_s))
        .collect();
    let spacing = skip_spacing(&found, session);
    let mut all = Repairs::default();
    let mut copy: Option<Session> = None;
    for (index, ((entry, trial), f)) in session.iter().zip(found).enumerate() {
        let file = || entry.file.clone();
        all.repeats
            .extend(f.twice.iter().map(|&(row, step_m)| Repeat {
                file: file(),
                row,
                t_s: trial.t_s[row],
                step_m,
            }));
        all.slips
            .extend(f.lost_in_file().map(|(after_row, samples, step_m)| Slip {
                file: file(),
                after_row,
                t_s: trial.t_s[after_row],
                samples,
                step_m,
            }));
        all.skips.extend(f.skips.iter().map(|&row| {
            let row = file_row(&f.removed, row);
            Skip {
                file: file(),
                row,
                t_s: trial.t_s[row],
            }
        }));
        all.jumps
            .extend(f.jumps.iter().map(|&(channel, row, step_m)| {
                let row = file_row(&f.removed, row);
                Jump {
                    file: file(),
                    channel,
                    row,
                    t_s: trial.t_s[row],
                    step_m,
                }
            }));
        if let Some(t) = mended(trial, f, spacing, period_s) {
            copy.get_or_insert_with(|| session.clone()).trials[index] = t;
        }
    }
    (copy, all)
}

/// `trial` mended by what [`look`] found in it, `f`: its repeats taken out, its
/// encoder's jumps levelled, its position retimed at its skips ([`retimed`], `spacing`
/// rows between skips), its lost samples put back, its time renumbered at `period_s`;
/// `None` when `f` found nothing.
fn mended(trial: &Trial, f: Found, spacing: f64, period_s: f64) -> Option<Trial> {
    if f.removed.is_empty() && f.lost.is_empty() && f.skips.is_empty() && f.jumps.is_empty() {
        return None;
    }
    let mut work = f.work.unwrap_or_else(|| trial.clone());
    for (channel, p) in [("x_m", &mut work.x_m), ("y_m", &mut work.y_m)] {
        let here: Vec<(usize, f64)> = f
            .jumps
            .iter()
            .filter(|j| j.0 == channel)
            .map(|j| (j.1, j.2))
            .collect();
        if !here.is_empty() {
            *p = jump::levelled(p, &here);
        }
    }
    if !f.skips.is_empty() {
        work.x_m = retimed(&work.x_m, &f.skips, spacing);
        work.y_m = retimed(&work.y_m, &f.skips, spacing);
    }
    let runs: Vec<(usize, usize)> = f.lost.iter().map(|r| (r.0, r.1)).collect();
    Some(repaired(&work, &runs, period_s))
}

/// The rows between a position sensor's skipped readings: the median spacing of
/// consecutive skips within the session's trials where at least [`MIN_SPACINGS`]
/// exist; else the longest trial's rows (a clock so near the log's that a trial holds
/// at most one skip: the readings' age then changes by little within a trial).
fn skip_spacing(found: &[Found], session: &Session) -> f64 {
    let mut spacings: Vec<f64> = found
        .iter()
        .flat_map(|f| f.skips.windows(2).map(|w| (w[1] - w[0]) as f64))
        .collect();
    if spacings.len() >= MIN_SPACINGS {
        super::stats::upper_median(&mut spacings)
    } else {
        session
            .trials
            .iter()
            .map(|t| t.x_m.len() as f64)
            .fold(1.0, f64::max)
    }
}

/// The fewest spacings between skips from which their median is the clock's.
pub const MIN_SPACINGS: usize = 3;

/// A position channel `v` whose sensor skipped a reading at each of `skips` (ascending
/// rows), on the log's rows (module docs): each row's reading is `a` of a row old, `a`
/// rising from half of `1/(d + 1)` at a skip by `1/(d + 1)` a row to the next skip `d`
/// rows on (a run of `d` rows shows `d + 1` readings; `d` is `spacing` past the last
/// skip and before the first, and where the next is more than half as far again away:
/// a skip not seen), and each row's value is the cubic through the four readings
/// around it at their times.
fn retimed(v: &[f64], skips: &[usize], spacing: f64) -> Vec<f64> {
    let n = v.len();
    if n < 4 || skips.is_empty() {
        return v.to_vec();
    }
    let times: Vec<f64> = (0..n)
        .map(|k| {
            let at = skips.partition_point(|&s| s <= k);
            // The skip this row's run of readings began at (one unseen, a spacing
            // before the first), and the rows to the next.
            let (from, span) = if at == 0 {
                (skips[0] as f64 - spacing, spacing)
            } else {
                let s = skips[at - 1];
                let span = skips
                    .get(at)
                    .map(|&next| (next - s) as f64)
                    .filter(|d| *d < 1.5 * spacing)
                    .unwrap_or(spacing);
                (s as f64, span)
            };
            // A run of `span` rows holds `span + 1` readings: each row's is 1/(span + 1)
            // of a row older than the last's, from half that at the skip.
            let age = ((k as f64 - from + 0.5) / (span + 1.0)).rem_euclid(1.0);
            k as f64 - age
        })
        .collect();
    (0..n)
        .map(|k| {
            let start = k.saturating_sub(1).min(n - 4);
            let nodes = start..start + 4;
            super::hold::lagrange(&times[nodes.clone()], &v[nodes], k as f64)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reaches;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// A reach at 1 kHz on both axes (0.25 m along y, 0.1 m along x, in 0.6 s, minimum
    /// jerk; 1.3 m/s peak speed along y) with 0.3 µm of white noise, `len` samples.
    fn reach(seed: u64, len: usize) -> (Vec<f64>, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let rows = || (0..len).map(|i| i as f64);
        let x = reaches::noisy(&mut rng, 0.1, 0.0, rows());
        let y = reaches::noisy(&mut rng, 0.25, 0.0, rows());
        (x, y)
    }

    /// Drops row `k` of both channels: what a logger that lost it writes.
    fn drop_row(v: &[f64], k: usize) -> Vec<f64> {
        v.iter()
            .enumerate()
            .filter(|&(i, _)| i != k)
            .map(|(_, &x)| x)
            .collect()
    }

    #[test]
    fn runs_of_one_to_three_lost_samples_are_found_and_put_back_to_the_noise() {
        // Runs of one, two and three samples lost at 0.15, 0.3 (peak speed) and 0.5 s,
        // on ten noise draws: each found after the row before it with its length, and
        // put back within 2 µm (one) or 3 µm (two, three) of the clean samples: five
        // standard deviations of the difference between the cubic's noise (0.97 × 0.3 µm
        // for one, at most 1.39 × 0.3 µm in the middle of a gap of three) and the clean
        // sample's own (0.3 µm) is 2.1 and 2.6 µm, and the cubic's error on the reach
        // itself is about 1 nm (the fourth derivative, 700 m/s⁴ at most, times the node
        // polynomial's 36 ms⁴ over 24). Left lost, the rows would be off by one to three
        // periods' travel, 0.65–2 mm at peak speed.
        for seed in 0..10 {
            let (x, y) = reach(seed, 2000);
            for (lost, bound) in [(1, 2.2e-6), (2, 3e-6), (3, 3e-6)] {
                let (mut xs, mut ys) = (x.clone(), y.clone());
                for k in [500, 300, 150] {
                    for _ in 0..lost {
                        xs = drop_row(&xs, k);
                        ys = drop_row(&ys, k);
                    }
                }
                let at: Vec<(usize, usize)> = find(&xs, &ys).iter().map(|r| (r.0, r.1)).collect();
                let expected = vec![(150, lost), (300 - lost, lost), (500 - 2 * lost, lost)];
                assert_eq!(at, expected, "seed {seed}, {lost} lost");
                let trial = Trial {
                    x_m: xs.clone(),
                    y_m: ys.clone(),
                    ..Trial::default()
                };
                let t = repaired(&trial, &at, 1e-3);
                assert_eq!(t.y_m.len(), 2000);
                assert!((t.t_s[1999] - 1.999).abs() < 1e-12);
                for start in [150, 300, 500] {
                    for k in start..start + lost {
                        assert!((t.y_m[k] - y[k]).abs() < bound, "seed {seed} row {k}");
                        assert!((t.x_m[k] - x[k]).abs() < bound, "seed {seed} row {k}");
                    }
                }
            }
        }
    }

    #[test]
    fn glitches_stale_frames_and_slow_slips_are_not_slips() {
        let (x, y) = reach(4, 2000);
        assert!(find(&x, &y).is_empty());
        // A spike of 1 mm and a stale frame at peak speed: dipoles in the step.
        let mut g = y.clone();
        g[300] += 1e-3;
        g[700] = g[699];
        assert!(find(&x, &g).is_empty());
        // A lost sample at rest (before the reach): nothing to see, nothing to mend.
        let (xs, ys) = (drop_row(&x, 20), drop_row(&y, 20));
        assert!(find(&xs, &ys).is_empty());
        // One channel alone doubling its step (a glitch shaped like a slip on y only,
        // x not following) is not a slip.
        let mut one = y.clone();
        for v in &mut one[301..] {
            *v += y[300] - y[299];
        }
        assert!(find(&x, &one).is_empty());
    }

    /// [`look`] and [`mended`] on one trial (its skips spaced by its length): the
    /// mended trial, its repeats, and its lost runs with the file's row before each.
    #[allow(clippy::type_complexity)]
    fn mend(
        trial: &Trial,
        search: bool,
        period_s: f64,
    ) -> (Option<Trial>, (Vec<(usize, f64)>, Vec<(usize, usize, f64)>)) {
        let f = look(trial, search, period_s);
        let twice = f.twice.clone();
        let lost = f.lost_in_file().collect();
        let spacing = trial.x_m.len() as f64;
        (mended(trial, f, spacing, period_s), (twice, lost))
    }

    /// A trial of `x, y` and a force of 0.05 N of noise on each axis, as a rig read at
    /// every row records it.
    fn trial_of(x: Vec<f64>, y: Vec<f64>, seed: u64) -> Trial {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, 0.05).unwrap();
        let n = x.len();
        let mut force = || (0..n).map(|_| noise.sample(&mut rng)).collect::<Vec<f64>>();
        Trial {
            t_s: (0..n).map(|k| k as f64 * 1e-3).collect(),
            fx_n: force(),
            fy_n: force(),
            pert_fx_n: vec![0.0; n],
            pert_fy_n: vec![0.0; n],
            x_m: x,
            y_m: y,
            ..Trial::default()
        }
    }

    #[test]
    fn a_position_sensor_faster_than_the_log_is_retimed_not_put_back() {
        // A position sensor at 1010 Hz (a reading every 0.99 rows): the log shows the
        // latest, so one reading in a hundred is never shown and the rest are up to a
        // row old. The controller's reference (the reach on the log's clock) steps on.
        for seed in 0..4 {
            let period = 0.99;
            let taken: Vec<f64> = (0..2100).map(|j| j as f64 * period - 0.63).collect();
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let xs = reaches::noisy(&mut rng, 0.1, 0.0, taken.iter().copied());
            let ys = reaches::noisy(&mut rng, 0.25, 0.0, taken.iter().copied());
            let shown: Vec<usize> = (0..2000)
                .map(|k| taken.partition_point(|&t| t <= k as f64) - 1)
                .collect();
            let mut t = trial_of(
                shown.iter().map(|&j| xs[j]).collect(),
                shown.iter().map(|&j| ys[j]).collect(),
                seed,
            );
            let reach = |extent: f64| -> Vec<f64> {
                (0..2000)
                    .map(|k| reaches::min_jerk(extent, 0.0, f64::from(k) / reaches::RATE_HZ))
                    .collect()
            };
            t.ref_x_m = Some(reach(0.1));
            t.ref_y_m = Some(reach(0.25));
            let f = look(&t, true, 1e-3);
            // The skips where the reach moves faster than 20 µm a row, found as such
            // (none as a lost sample), one reading in a hundred.
            assert!(f.lost.is_empty(), "seed {seed}: {:?}", f.lost);
            let skipped: Vec<usize> = (1..2000)
                .filter(|&k| shown[k] == shown[k - 1] + 2)
                .collect();
            assert!(f.skips.len() >= 4, "seed {seed}: {:?}", f.skips);
            assert!(f.skips.iter().all(|s| skipped.contains(s)), "seed {seed}");
            let (first, last) = (f.skips[0], f.skips[f.skips.len() - 1]);
            let spacing = 1.0 / (1.0 - period);
            let fixed = mended(&t, f, spacing, 1e-3).unwrap();
            // Between the first and the last skip: as shown, up to a row's travel off
            // the reach on the log's rows (0.78 mm at peak speed); retimed, within the
            // age's error, at most half of 1/101 of a row (3.9 µm at peak speed), and
            // the cubic's weights on the 0.3 µm noise: 6 µm.
            let truth = reach(0.25);
            let off = |v: &[f64]| {
                (first..last)
                    .map(|k| (v[k] - truth[k]).abs())
                    .fold(0.0, f64::max)
            };
            assert!(off(&t.y_m) > 0.3e-3, "seed {seed}: {}", off(&t.y_m));
            assert!(off(&fixed.y_m) < 6e-6, "seed {seed}: {}", off(&fixed.y_m));
            // The force is untouched, row for row.
            assert_eq!(fixed.fx_n, t.fx_n);
            // A frame the logger lost (every column, the reference too) is still a
            // lost sample.
            let lost = each_column(&t, |v| drop_row(v, last + 10), 1e-3);
            let g = look(&lost, true, 1e-3);
            assert_eq!(
                g.lost.iter().map(|r| r.0).collect::<Vec<_>>(),
                vec![last + 10],
                "seed {seed}"
            );
        }
    }

    /// `t` with row `k` written twice in every column, as a logger whose clock ran
    /// ahead writes it; the time renumbered.
    fn written_twice(t: &Trial, k: usize) -> Trial {
        let twice = |v: &[f64]| {
            let mut out = v.to_vec();
            out.insert(k, v[k]);
            out
        };
        each_column(t, twice, 1e-3)
    }

    #[test]
    fn a_frame_written_twice_is_taken_out_and_the_trial_is_the_clean_one() {
        for seed in 0..10 {
            let (x, y) = reach(seed, 2000);
            let clean = trial_of(x, y, seed);
            assert!(find_repeats(&clean).is_empty(), "seed {seed}");
            let twice = written_twice(&written_twice(&clean, 300), 151);
            let found: Vec<usize> = find_repeats(&twice).iter().map(|r| r.0).collect();
            assert_eq!(found, vec![152, 302], "seed {seed}");
            // A frame written three and four times (a run of two and three repeats)
            // is taken out whole.
            let thrice = written_twice(&written_twice(&clean, 300), 300);
            let more = written_twice(&written_twice(&written_twice(&thrice, 450), 450), 450);
            let found: Vec<usize> = find_repeats(&more).iter().map(|r| r.0).collect();
            assert_eq!(found, vec![301, 302, 451, 452, 453], "seed {seed}");
            assert_eq!(mend(&more, true, 1e-3).0.unwrap(), clean, "seed {seed}");
            let (fixed, (repeats, slips)) = mend(&twice, true, 1e-3);
            assert!(slips.is_empty(), "seed {seed}: {slips:?}");
            assert_eq!(repeats.len(), 2);
            // Exactly the clean trial: the repeats are copies, so taking them out
            // leaves the recorded rows.
            assert_eq!(fixed.unwrap(), clean, "seed {seed}");
        }
    }

    #[test]
    fn a_stale_frame_is_a_repeat_and_a_lost_sample_and_is_mended_as_both() {
        // The logger wrote row 299 again in place of row 300 (lost): the repeat is
        // taken out, and the sample it hid is put back by the cubic, within 2 µm of the
        // clean one (the lost-sample test's tolerance), and counted in the file's rows.
        for seed in 0..10 {
            let (x, y) = reach(seed, 2000);
            let clean = trial_of(x, y, seed);
            let mut stale = clean.clone();
            stale.x_m[300] = stale.x_m[299];
            stale.y_m[300] = stale.y_m[299];
            stale.fx_n[300] = stale.fx_n[299];
            stale.fy_n[300] = stale.fy_n[299];
            let (fixed, (repeats, slips)) = mend(&stale, true, 1e-3);
            let t = fixed.unwrap();
            assert_eq!(repeats.iter().map(|r| r.0).collect::<Vec<_>>(), vec![300]);
            assert_eq!(slips.iter().map(|s| s.0).collect::<Vec<_>>(), vec![299]);
            assert_eq!(t.len(), 2000);
            assert!((t.y_m[300] - clean.y_m[300]).abs() < 2e-6, "seed {seed}");
            assert!((t.x_m[300] - clean.x_m[300]).abs() < 2e-6, "seed {seed}");
        }
    }

    #[test]
    fn rows_that_repeat_at_rest_or_in_one_channel_are_not_repeats() {
        let (x, y) = reach(7, 2000);
        let clean = trial_of(x, y, 7);
        // At rest (before the reach): a repeat there moves no fit and is left.
        assert!(find_repeats(&written_twice(&clean, 20)).is_empty());
        // The position repeating at peak speed with the force changing is not a frame
        // written twice (it is a stale encoder read, the glitch rule's).
        let mut one = clean.clone();
        one.y_m[300] = one.y_m[299];
        one.x_m[300] = one.x_m[299];
        assert!(find_repeats(&one).is_empty());
        // Without a force sensor (constant force columns) nothing is searched.
        let mut no_sensor = written_twice(&clean, 300);
        no_sensor.fx_n.iter_mut().for_each(|v| *v = 0.0);
        no_sensor.fy_n.iter_mut().for_each(|v| *v = 0.0);
        assert!(find_repeats(&no_sensor).is_empty());
        // Found at peak speed, but a trial with a held channel is not searched.
        let twice = written_twice(&clean, 300);
        assert_eq!(mend(&twice, true, 1e-3).1.0.len(), 1);
        assert!(mend(&twice, false, 1e-3).1.0.is_empty());
    }
}
