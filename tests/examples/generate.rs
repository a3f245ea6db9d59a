//! Writes one generated session hiding a catalog effect, for looking at it by hand:
//!
//! ```sh
//! cargo run --release -p rigtwin-tests --example generate -- stretch-reflex 7 /tmp/gen
//! cargo run --release -p rigtwin-tests --example generate -- stretch-reflex 2 /tmp/q --no-motor-noise
//! cargo run --release -p rigtwin-tests --example generate -- stretch-reflex 7 /tmp/r --repetitions 9
//! cargo run --release -p rigtwin-tests --example generate -- stretch-reflex 7 /tmp/s --repetitions 9 --pulse 0.05,30
//! cargo run --release -p rigtwin-tests --example generate -- none 7 /tmp/i --ideal
//! cargo run --release -p rigtwin-tests --example generate -- none 7 /tmp/h --arm-inertia-scale 1.15
//! cargo run --release -p rigtwin-tests --example generate -- none 7 /tmp/f --movement 1.0
//! cargo run --release -p rigtwin-tests --example generate -- grip-compliance 3 /tmp/g --grip 1000,10
//! cargo run --release -p rigtwin-tests --example generate -- none 7 /tmp/l --lateral
//! cargo run --release -p rigtwin-tests --example generate -- handle-mass 7 /tmp/c --cardinal
//! cargo run --release -p rigtwin-tests --example generate -- none 7 /tmp/p --angles 0,180
//! cargo run --release -p rigtwin-tests --example generate -- grip-compliance 7 /tmp/o --centre-out
//! cargo run --release -p rigtwin-tests --example generate -- none 7 /tmp/b --centre-out --out-and-back 0.25
//! rigtwin diagnose /tmp/gen/<session>
//! ```
//!
//! Arguments: effect name (`none`, a catalog name, or two joined by `+`), seed, output folder (new or
//! empty); optional fourth: trials (default 32, or a third more than the pulses with
//! `--repetitions`). `--no-motor-noise` switches the arm's motor noise off, keeping
//! subject and effect; `--repetitions N` gives N pulses per angle (default 3, the
//! shared sessions'); `--pulse SECONDS,NEWTONS` sets the force pulse's duration and
//! amplitude (default the protocol's 0.15 s, 15 N; `Design::reflex_study` is
//! `--repetitions 9 --pulse 0.05,30`); `--ideal` drops the rig's and subject's nuisances
//! (on by default: a lab's rig); `--arm-inertia-scale F` multiplies the simulated arm's
//! segment masses and moments of inertia by `F` (a subject heavier or lighter than the
//! tables the diagnosis assumes; default 1); `--movement SECONDS` sets the reach's
//! duration (default the protocol's 3 s); `--grip N_PER_M,N_S_PER_M` hides a grip of that
//! stiffness and damping instead of the drawn one (effect `grip-compliance` only);
//! `--lateral` lays the reaches along `x` instead of `y` (`Design::lateral`);
//! `--angles A,B,…` fires the pulses in those directions (degrees from `+x` toward `+y`)
//! instead of the protocol's eight, as many per direction as make the shared layout's
//! 24 pulses unless `--repetitions` says (`Design::with_angles`); `--cardinal` is
//! `--angles 0,90,180,270` (`Design::cardinal`); `--centre-out` sends the reaches to
//! three goals (`Design::centre_out`, `CENTRE_OUT_M`); `--out-and-back SECONDS` brings
//! each reach back to its start after that long at the goal, in one trial
//! (`Design::back_after_s`). Prints the session folder and what it hides.

use rigtwin_tests::generator::{
    CARDINAL_DEG, CENTRE_OUT_M, Design, EFFECTS, Hidden, generate_design, generate_hidden,
    parse_grip, parse_pulse,
};

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let usage = || {
        format!(
            "usage: generate <effect> <seed> <out> [trials] [--no-motor-noise] [--repetitions N] [--pulse SECONDS,NEWTONS] [--ideal] [--arm-inertia-scale F] [--movement SECONDS] [--grip N_PER_M,N_S_PER_M] [--lateral] [--angles DEGREES,…] [--cardinal] [--centre-out] [--out-and-back SECONDS]; effects {EFFECTS:?}"
        )
    };
    let mut positional = Vec::new();
    let mut motor_noise = true;
    let mut repetitions = None;
    let mut pulse = None;
    let mut grip = None;
    let mut ideal = false;
    let mut lateral = false;
    let mut centre_out = false;
    let mut angles: Option<Vec<f64>> = None;
    let mut arm_inertia_scale = 1.0;
    let mut movement_s = None;
    let mut back_after_s = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--no-motor-noise" => motor_noise = false,
            "--ideal" => ideal = true,
            "--lateral" => lateral = true,
            "--centre-out" => centre_out = true,
            "--cardinal" => angles = Some(CARDINAL_DEG.to_vec()),
            "--angles" => {
                let v = args
                    .next()
                    .ok_or_else(|| format!("--angles needs DEGREES,…; {}", usage()))?;
                let list = v
                    .split(',')
                    .map(|a| {
                        a.trim()
                            .parse::<f64>()
                            .ok()
                            .filter(|a| a.is_finite())
                            .ok_or_else(|| {
                                format!("--angles {v:?}: {a:?} is not a number of degrees")
                            })
                    })
                    .collect::<Result<Vec<f64>, String>>()?;
                angles = Some(list);
            }
            "--repetitions" => {
                let n = args
                    .next()
                    .ok_or_else(|| format!("--repetitions needs a number; {}", usage()))?;
                let n: u32 = n.parse().map_err(|e| format!("--repetitions {n:?}: {e}"))?;
                if n == 0 {
                    return Err("--repetitions must be at least 1".into());
                }
                repetitions = Some(n);
            }
            "--arm-inertia-scale" => {
                let v = args
                    .next()
                    .ok_or_else(|| format!("--arm-inertia-scale needs a factor; {}", usage()))?;
                let f: f64 = v
                    .parse()
                    .map_err(|e| format!("--arm-inertia-scale {v:?}: {e}"))?;
                if !(f.is_finite() && f > 0.0) {
                    return Err(
                        format!("--arm-inertia-scale must be a positive factor, got {v}").into(),
                    );
                }
                arm_inertia_scale = f;
            }
            "--out-and-back" => {
                let v = args.next().ok_or_else(|| {
                    format!("--out-and-back needs seconds at the goal; {}", usage())
                })?;
                let s: f64 = v
                    .parse()
                    .map_err(|e| format!("--out-and-back {v:?}: {e}"))?;
                if !(s.is_finite() && s >= 0.0) {
                    return Err(format!(
                        "--out-and-back must be a non-negative time at the goal in s, got {v}"
                    )
                    .into());
                }
                back_after_s = Some(s);
            }
            "--movement" => {
                let v = args
                    .next()
                    .ok_or_else(|| format!("--movement needs seconds; {}", usage()))?;
                let s: f64 = v.parse().map_err(|e| format!("--movement {v:?}: {e}"))?;
                if !(s.is_finite() && s > 0.0) {
                    return Err(
                        format!("--movement must be a positive duration in s, got {v}").into(),
                    );
                }
                movement_s = Some(s);
            }
            "--grip" => {
                let v = args
                    .next()
                    .ok_or_else(|| format!("--grip needs N_PER_M,N_S_PER_M; {}", usage()))?;
                grip = Some(parse_grip(&v).map_err(|e| format!("--{e}"))?);
            }
            "--pulse" => {
                let v = args
                    .next()
                    .ok_or_else(|| format!("--pulse needs SECONDS,NEWTONS; {}", usage()))?;
                pulse = Some(parse_pulse(&v).map_err(|e| format!("--{e}"))?);
            }
            s if s.starts_with("--") => {
                return Err(format!("unexpected argument {s:?}; {}", usage()).into());
            }
            _ => positional.push(a),
        }
    }
    let [effect, seed, out, rest @ ..] = positional.as_slice() else {
        return Err(usage().into());
    };
    if let Some(bad) = rest.get(1) {
        return Err(format!("unexpected argument {bad:?}; {}", usage()).into());
    }
    let seed: u64 = seed.parse().map_err(|e| format!("seed {seed:?}: {e}"))?;
    let mut design = match (&angles, repetitions) {
        // The shared layout's 24 pulses over the directions given, unless told.
        (Some(a), r) => Design::with_angles(a, r.unwrap_or_else(|| 24u32.div_ceil(a.len() as u32))),
        (None, Some(r)) => Design::with_pulses(r),
        (None, None) => Design::SHARED,
    };
    if let Some(t) = rest.first() {
        design.trials = t.parse().map_err(|e| format!("trials {t:?}: {e}"))?;
    }
    design.motor_noise = motor_noise;
    design.pulse = pulse;
    if ideal {
        design.nuisance = None;
    }
    design.arm_inertia_scale = arm_inertia_scale;
    design.movement_s = movement_s;
    design.lateral = lateral;
    design.back_after_s = back_after_s;
    if centre_out {
        design.targets_m = Some(CENTRE_OUT_M.to_vec());
    }
    let out = std::path::Path::new(out.as_str());
    let g = match grip {
        Some((k, b)) if effect == "grip-compliance" => {
            generate_hidden(Hidden::grip(k, b), seed, &design, out)?
        }
        Some(_) => {
            return Err(
                format!("--grip goes with the effect grip-compliance, not {effect:?}").into(),
            );
        }
        None => generate_design(effect, seed, &design, out)?,
    };
    println!("{}", g.dir.display());
    println!("hidden {} {:?}", g.hidden.effect, g.hidden.parameters);
    Ok(())
}
