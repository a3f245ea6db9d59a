//! A sweep as a Slurm job array: one task per shard, and the merge as a job that starts
//! when every task has succeeded (`--dependency=afterok`).
//!
//! The requests come from a measured run, not a guess: the wall time of a task is its
//! runs' expected simulated time × the measured wall time per simulated second of one
//! run, on `cpus_per_task` workers, doubled and with 5 minutes added (a shared node is
//! slower than the node that measured; a task that hits its limit is killed and its
//! shard missing, which the merge then names); the memory is the measured run's peak
//! resident size × the workers, × 1.5, at least 256 MB.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::SweepFile;
use super::run::Run;
use crate::rehearse::cost::Cost;

/// What the scripts ask of the cluster.
#[derive(Debug, Clone, PartialEq)]
pub struct SlurmPlan {
    /// Array tasks (shards).
    pub tasks: usize,
    /// At most this many tasks at once (`%LIMIT`); `None`: as many as the cluster gives.
    pub max_running: Option<usize>,
    /// CPUs per task (the task's `--jobs`).
    pub cpus_per_task: usize,
    /// Partition, if the cluster wants one named.
    pub partition: Option<String>,
    /// Account, if the cluster wants one named.
    pub account: Option<String>,
    /// The `rigtwin` binary the tasks run (absolute).
    pub binary: PathBuf,
    /// The sweep file (absolute).
    pub sweep: PathBuf,
    /// The sweep's folder (absolute).
    pub out: PathBuf,
    /// Measured wall time per simulated second of one run, s/s.
    pub wall_per_simulated_s: f64,
    /// Measured peak resident memory of one run, bytes.
    pub peak_bytes: f64,
}

/// A run's expected simulated time, s (trials and the unperturbed twins of its pulses):
/// its grid point's protocol decides it, whichever subject is drawn into it.
#[must_use]
pub fn simulated_s(sweep: &SweepFile, run: &Run) -> f64 {
    let p = sweep.protocol_at(run.point, run.size);
    let cost = Cost::of(p, 1, sweep.max_trials, 1, false);
    let twins = if p.kind == crate::protocol::ProtocolKind::ReachPerturb {
        let trials = cost.trials as f64;
        let perturbed = p.reach().perturbed() as f64;
        let total = p.trials_per_subject().max(1) as f64;
        // The pulses fall at random among the trials: the first `trials` hold their share.
        perturbed * (trials / total).min(1.0) * p.trial_s().0
    } else {
        0.0
    };
    cost.simulated_s + twins
}

/// Wall time of the slowest task, s (before the margin).
#[must_use]
pub fn task_wall_s(sweep: &SweepFile, plan: &SlurmPlan) -> f64 {
    (0..plan.tasks)
        .map(|k| {
            super::table::shard_runs(k, plan.tasks, sweep.runs())
                .map(|i| simulated_s(sweep, &Run::at(sweep, i)))
                .sum::<f64>()
                * plan.wall_per_simulated_s
                / plan.cpus_per_task.max(1) as f64
        })
        .fold(0.0, f64::max)
}

fn hms(s: f64) -> String {
    let s = s.ceil().max(60.0) as u64;
    let m = s.div_ceil(60);
    format!("{:02}:{:02}:00", m / 60, m % 60)
}

fn quote(p: &Path) -> String {
    format!("'{}'", p.display().to_string().replace('\'', r"'\''"))
}

/// The scripts: `(array.sbatch, merge.sbatch, submit.sh)`.
#[must_use]
pub fn scripts(sweep: &SweepFile, plan: &SlurmPlan) -> (String, String, String) {
    let n = plan.tasks.max(1);
    let time = hms(2.0 * task_wall_s(sweep, plan) + 300.0);
    let mem_mb = ((1.5 * plan.peak_bytes * plan.cpus_per_task.max(1) as f64) / 1.0e6)
        .ceil()
        .max(256.0) as u64;
    let logs = plan.out.join("slurm").join("logs");
    let mut common = String::new();
    if let Some(p) = &plan.partition {
        let _ = writeln!(common, "#SBATCH --partition={p}");
    }
    if let Some(a) = &plan.account {
        let _ = writeln!(common, "#SBATCH --account={a}");
    }
    let limit = plan.max_running.map_or(String::new(), |l| format!("%{l}"));
    let array = format!(
        "#!/bin/bash
# rigtwin sweep `{name}`: {runs} runs in {n} array tasks; written by
# `rigtwin sweep ... --emit slurm`. Each task runs one shard (runs K, K+{n}, ...) and
# writes {out}/shards/shard-K-of-N.csv atomically; a requeued task starts its shard again.
# Requests: {time} per task (2 x the measured cost + 5 min), {mem_mb} MB.
#SBATCH --job-name=rigtwin-{name}
#SBATCH --array=0-{last}{limit}
#SBATCH --output={logs}/task-%A_%a.log
#SBATCH --time={time}
#SBATCH --mem={mem_mb}M
#SBATCH --cpus-per-task={cpus}
#SBATCH --requeue
{common}set -euo pipefail
exec {bin} sweep {sweep} --out {outq} --shard \"${{SLURM_ARRAY_TASK_ID}}/{n}\" --jobs \"${{SLURM_CPUS_PER_TASK:-{cpus}}}\" --yes
",
        name = sweep.name,
        runs = sweep.runs(),
        out = plan.out.display(),
        last = n - 1,
        logs = logs.display(),
        cpus = plan.cpus_per_task.max(1),
        bin = quote(&plan.binary),
        sweep = quote(&plan.sweep),
        outq = quote(&plan.out),
    );
    let merge = format!(
        "#!/bin/bash
# Merges the shards of sweep `{name}` into {out}/sweep.csv and sweep.md; submitted with
# --dependency=afterok on the array, so it runs only when every task succeeded.
#SBATCH --job-name=rigtwin-{name}-merge
#SBATCH --output={logs}/merge-%j.log
#SBATCH --time=00:15:00
#SBATCH --mem=512M
#SBATCH --cpus-per-task=1
{common}set -euo pipefail
exec {bin} sweep merge {outq}
",
        name = sweep.name,
        out = plan.out.display(),
        logs = logs.display(),
        bin = quote(&plan.binary),
        outq = quote(&plan.out),
    );
    let submit = format!(
        "#!/bin/bash
# Submits sweep `{name}`: the array of {n} tasks, then the merge after it.
set -euo pipefail
here=\"$(cd \"$(dirname \"$0\")\" && pwd)\"
array=$(sbatch --parsable \"$here/array.sbatch\")
array=${{array%%;*}}
merge=$(sbatch --parsable --dependency=afterok:\"$array\" \"$here/merge.sbatch\")
merge=${{merge%%;*}}
echo \"array job $array ({n} tasks), merge job $merge after it; results in {out}\"
",
        name = sweep.name,
        out = plan.out.display(),
    );
    (array, merge, submit)
}

/// Writes the scripts into `<out>/slurm/` (and its `logs/`, which Slurm does not make);
/// returns their paths, `submit.sh` last.
///
/// # Errors
/// An I/O error, with the path.
pub fn write(sweep: &SweepFile, plan: &SlurmPlan) -> Result<Vec<PathBuf>, String> {
    let dir = plan.out.join("slurm");
    std::fs::create_dir_all(dir.join("logs")).map_err(|e| format!("{}: {e}", dir.display()))?;
    let (array, merge, submit) = scripts(sweep, plan);
    let mut out = Vec::new();
    for (name, text) in [
        ("array.sbatch", array),
        ("merge.sbatch", merge),
        ("submit.sh", submit),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))
                .map_err(|e| format!("{}: {e}", path.display()))?;
        }
        out.push(path);
    }
    Ok(out)
}
