//! `rigtwin estimate`: the device's estimators on any session, measured or simulated.

use std::path::PathBuf;

use anyhow::Context as _;
use rigtwin::protocol::{EstimateConfig, EstimateMode};
use rigtwin::report::{borner_on_session, estimate::push_onsets, piovesan_on_session};
use rigtwin::session::Session;

/// Estimate impedance from a session's perturbed trials. Force-pulse trials: the
/// involuntary impedance of Börner et al. (000_*): Savitzky-Golay jerk, 1 Hz high-pass,
/// 150 ms window, least squares for D and a symmetric K with the subject's endpoint
/// inertia (default arm rescaled to the manifest's segment lengths, at each onset
/// posture) as the a-priori M_BSP. Trials with position perturbations (`pert_x_m`,
/// `pert_y_m` columns, as rigtwin's hold protocols record them): the windowed K/B
/// regression of Piovesan et al. (001_*), 10-cycle windows, two perturbations a cycle.
#[derive(Debug, clap::Args)]
#[command(after_help = "\
Examples:
  rigtwin estimate ../shared/recordings/example-none
  rigtwin estimate out/reach-perturb-1/S01 --json
  rigtwin estimate session/ --t-est-s 0.1 --mode consistent
  rigtwin estimate ../shared/recordings/example-friction --rerun save=k.rrd  # ellipses in the viewer")]
pub struct Args {
    /// Session directory (holds session.toml and trials/).
    pub session: PathBuf,

    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,

    /// Estimation window after the onset, s.
    #[arg(long, value_name = "S", default_value_t = 0.150)]
    pub t_est_s: f64,

    /// High-pass cut-off of the jerk, Hz (0: none).
    #[arg(long, value_name = "HZ", default_value_t = 1.0)]
    pub high_pass_hz: f64,

    /// How variational signals are formed: `seed` (as 000_* writes it) or `consistent`.
    #[arg(long, value_name = "MODE", default_value = "seed", value_parser = ["seed", "consistent"])]
    pub mode: String,

    /// Windowed regression: isotropic inertia moved with the handle besides the handle
    /// itself, kg (e.g. 1.87 for the 001_* calibration rig). Default: the subject's
    /// arm endpoint inertia at the trial's start.
    #[arg(long, value_name = "KG")]
    pub m_hat_kg: Option<f64>,

    #[cfg(feature = "rerun")]
    #[command(flatten)]
    pub rerun: rigtwin::viz::RerunArgs,
}

/// Streams the session and the ellipses of the estimate just printed (same settings).
#[cfg(feature = "rerun")]
fn stream(args: &Args, session: &Session, config: &EstimateConfig) -> anyhow::Result<()> {
    let Some(target) = &args.rerun.rerun else {
        return Ok(());
    };
    let streamed = super::view::stream_session(
        target,
        session,
        rigtwin::viz::DEFAULT_LIVE_RATE_HZ,
        config,
        args.m_hat_kg,
    )?;
    super::view::report_streamed(&streamed, target, args.json)?;
    Ok(())
}

fn run_piovesan(args: &Args, session: &Session) -> anyhow::Result<()> {
    if let Some(m) = args.m_hat_kg
        && !(m.is_finite() && m >= 0.0)
    {
        anyhow::bail!("--m-hat-kg must be >= 0, got {m}");
    }
    let trials = piovesan_on_session(session, args.m_hat_kg)
        .with_context(|| format!("estimating {}", args.session.display()))?;
    if args.json {
        let rows: Vec<serde_json::Value> = trials
            .iter()
            .map(|t| match t {
                Ok(t) => serde_json::to_value(t).unwrap_or(serde_json::Value::Null),
                Err(e) => serde_json::json!({ "error": e }),
            })
            .collect();
        let out = serde_json::json!({
            "session": args.session.display().to_string(),
            "method": "piovesan-windowed-regression",
            "trials": rows,
        });
        outln!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(());
    }
    outln!(
        "session    {} ({}, subject {}, {:.0} Hz)",
        args.session.display(),
        session.manifest.source.as_str(),
        session.manifest.subject.id,
        session.manifest.rate_hz
    );
    outln!("method     Piovesan windowed regression (mean over 10-cycle windows)");
    outln!(
        "trial  pushes  windows      K11      K12      K21      K22 [N/m]    B11    B22 [N s/m]    r²"
    );
    for t in &trials {
        match t {
            Ok(t) => outln!(
                "{:5}  {:6}  {:7}  {:7.1}  {:7.1}  {:7.1}  {:7.1}      {:6.2} {:6.2}         {:.3}",
                t.id,
                t.perturbations,
                t.windows,
                t.k_n_per_m[0][0],
                t.k_n_per_m[0][1],
                t.k_n_per_m[1][0],
                t.k_n_per_m[1][1],
                t.b_ns_per_m[0][0],
                t.b_ns_per_m[1][1],
                t.r2
            ),
            Err(e) => outln!("{e}"),
        }
    }
    Ok(())
}

fn mat(m: &[[f64; 2]; 2], se: &[[f64; 2]; 2]) -> [String; 2] {
    [0, 1].map(|r| {
        format!(
            "[{:8.2} ± {:6.2}, {:8.2} ± {:6.2}]",
            m[r][0], se[r][0], m[r][1], se[r][1]
        )
    })
}

/// Runs `rigtwin estimate`.
///
/// # Errors
/// An unreadable session (naming file, line and field), no perturbed trial, or an
/// estimator failure.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if !(args.t_est_s.is_finite() && args.t_est_s > 0.0) {
        anyhow::bail!("--t-est-s must be > 0, got {}", args.t_est_s);
    }
    if !(args.high_pass_hz.is_finite() && args.high_pass_hz >= 0.0) {
        anyhow::bail!("--high-pass-hz must be >= 0, got {}", args.high_pass_hz);
    }
    let session = Session::read(&args.session)
        .with_context(|| format!("reading session {}", args.session.display()))?;
    if session.manifest.axes != rigtwin::session::Axes::Both {
        return super::not_applicable(
            &args.session,
            &session,
            args.json,
            "estimate",
            "the impedance estimators need a subject's planar arm and force pulses; a rig of one axis has neither. What applies to it is `rigtwin diagnose`, which identifies the axis itself (moving mass, friction, the constant force it holds against, cogging, delay)",
        );
    }
    let has_pulses = session
        .manifest
        .trials
        .iter()
        .any(|t| t.perturbation.is_some());
    if !has_pulses && session.trials.iter().any(|t| !push_onsets(t).is_empty()) {
        run_piovesan(args, &session)?;
        #[cfg(feature = "rerun")]
        stream(args, &session, &EstimateConfig::default())?;
        return Ok(());
    }
    let config = EstimateConfig {
        t_est_s: args.t_est_s,
        high_pass_hz: args.high_pass_hz,
        mode: if args.mode == "consistent" {
            EstimateMode::Consistent
        } else {
            EstimateMode::Seed
        },
        ..EstimateConfig::default()
    };
    let est = borner_on_session(&session, &config)
        .with_context(|| format!("estimating {}", args.session.display()))?;
    if args.json {
        let out = serde_json::json!({
            "session": args.session.display().to_string(),
            "subject": session.manifest.subject.id,
            "source": session.manifest.source.as_str(),
            "method": "borner-involuntary-impedance",
            "t_est_s": config.t_est_s,
            "high_pass_hz": config.high_pass_hz,
            "result": est,
        });
        outln!("{}", serde_json::to_string_pretty(&out)?);
        #[cfg(feature = "rerun")]
        stream(args, &session, &config)?;
        return Ok(());
    }
    let m = &session.manifest;
    outln!(
        "session    {} ({}, subject {}, {:.0} Hz)",
        args.session.display(),
        m.source.as_str(),
        m.subject.id,
        m.rate_hz
    );
    outln!(
        "method     Börner involuntary impedance: {} force-pulse trials, T_est {:.0} ms, high-pass {} Hz",
        est.trials,
        config.t_est_s * 1e3,
        config.high_pass_hz
    );
    let mb = est.m_bsp_kg;
    outln!(
        "M_BSP      [[{:.3}, {:.3}], [{:.3}, {:.3}]] kg (a priori, arm endpoint inertia)",
        mb[0][0],
        mb[0][1],
        mb[1][0],
        mb[1][1]
    );
    let d = mat(&est.d_ns_per_m, &est.d_std_err_ns_per_m);
    let k = mat(&est.k_n_per_m, &est.k_std_err_n_per_m);
    outln!("D [N s/m]  {}\n           {}", d[0], d[1]);
    outln!("K [N/m]    {}\n           {}", k[0], k[1]);
    outln!(
        "fit        condition number {:.1}, relative RMS residual {:.3}  (± = jackknife s.e. over trials)",
        est.condition_number,
        est.nrmse
    );
    #[cfg(feature = "rerun")]
    stream(args, &session, &config)?;
    Ok(())
}
