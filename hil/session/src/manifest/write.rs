//! Writing `session.toml`: a fixed layout, so the same manifest always gives the same
//! bytes.

#[allow(clippy::wildcard_imports)]
use super::*;

fn float(v: f64) -> String {
    // `{:?}` is the shortest text that reads back to the same f64 and is valid TOML
    // (`5.0`, `0.15`, `1e-7`); values are finite by construction.
    format!("{v:?}")
}

fn string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

fn pair(v: [f64; 2]) -> String {
    format!("[{}, {}]", float(v[0]), float(v[1]))
}

fn key(k: &str) -> String {
    let bare = !k.is_empty()
        && k.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-');
    if bare { k.to_string() } else { string(k) }
}

fn extra(out: &mut String, map: &BTreeMap<String, toml::Value>) {
    for (k, v) in map {
        let _ = writeln!(out, "{} = {}", key(k), v);
    }
}

/// Writes one `[[trial]]` entry.
pub(crate) fn write_trial_entry(out: &mut String, t: &TrialEntry) {
    let _ = writeln!(out, "[[trial]]");
    let _ = writeln!(out, "id = {}", t.id);
    let _ = writeln!(out, "file = {}", string(&t.file));
    if let Some(sha) = t.sha256 {
        let _ = writeln!(out, "sha256 = \"{sha}\"");
    }
    let _ = writeln!(out, "kind = {}", string(t.kind.as_str()));
    if let Some(v) = t.start_m {
        let _ = writeln!(out, "start_m = {}", pair(v));
    }
    if let Some(v) = t.goal_m {
        let _ = writeln!(out, "goal_m = {}", pair(v));
    }
    if let Some(p) = &t.perturbation {
        let _ = writeln!(out, "\n[trial.perturbation]");
        let _ = writeln!(out, "kind = {}", string(p.kind.as_str()));
        let _ = writeln!(out, "onset_s = {}", float(p.onset_s));
        let _ = writeln!(out, "duration_s = {}", float(p.duration_s));
        match p.amplitude {
            Amplitude::ForceN(a) => {
                let _ = writeln!(out, "amplitude_n = {}", float(a));
            }
            Amplitude::PositionM(a) => {
                let _ = writeln!(out, "amplitude_m = {}", float(a));
            }
        }
        let _ = writeln!(out, "angle_deg = {}", float(p.angle_deg));
    }
}

impl Manifest {
    /// The manifest as TOML text, in the spec's layout. Deterministic: the same
    /// manifest always gives the same bytes.
    #[must_use]
    pub fn to_toml(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "format = \"{FORMAT}\"");
        let _ = writeln!(out, "format_version = {FORMAT_VERSION}");
        let _ = writeln!(out, "source = \"{}\"", self.source.as_str());
        let _ = writeln!(out, "rate_hz = {}", float(self.rate_hz));
        if self.axes != Axes::Both {
            let names: Vec<String> = self.axes.names().iter().map(|n| string(n)).collect();
            let _ = writeln!(out, "axes = [{}]", names.join(", "));
        }
        let _ = writeln!(out, "created = {}", string(&self.created));
        let d = &self.device;
        let _ = writeln!(out, "\n[device]");
        let _ = writeln!(out, "kind = {}", string(&d.kind));
        let _ = writeln!(out, "mass_kg = {}", pair(d.mass_kg));
        let _ = writeln!(out, "damping_n_s_per_m = {}", pair(d.damping_n_s_per_m));
        if let Some(v) = d.handle_mass_kg {
            let _ = writeln!(out, "handle_mass_kg = {}", float(v));
        }
        if let Some(v) = d.workspace_half_width_m {
            let _ = writeln!(out, "workspace_half_width_m = {}", float(v));
        }
        let s = &self.subject;
        let _ = writeln!(out, "\n[subject]");
        let _ = writeln!(out, "id = {}", string(&s.id));
        let _ = writeln!(out, "shoulder_m = {}", pair(s.shoulder_m));
        for (k, v) in [
            ("upper_arm_m", s.upper_arm_m),
            ("forearm_m", s.forearm_m),
            ("body_mass_kg", s.body_mass_kg),
        ] {
            if let Some(v) = v {
                let _ = writeln!(out, "{k} = {}", float(v));
            }
        }
        extra(&mut out, &s.extra);
        if let Some(sim) = &self.sim {
            let _ = writeln!(out, "\n[sim]");
            if let Some(seed) = sim.seed {
                let _ = writeln!(out, "seed = {seed}");
            }
            if let Some(p) = &sim.protocol {
                let _ = writeln!(out, "protocol = {}", string(p));
            }
            if let Some(m) = &sim.model {
                let _ = writeln!(out, "model = {}", string(m));
            }
            extra(&mut out, &sim.extra);
        }
        if let Some(t) = &self.timing {
            let _ = writeln!(out, "\n[timing]");
            let _ = writeln!(out, "period_us = {}", float(t.period_us));
            let _ = writeln!(out, "ticks = {}", t.ticks);
            let _ = writeln!(out, "missed_deadlines = {}", t.missed_deadlines);
            let _ = writeln!(out, "max_consecutive_misses = {}", t.max_consecutive_misses);
            for (name, p) in [("wake_latency", t.wake_latency), ("loop_time", t.loop_time)] {
                let _ = writeln!(
                    out,
                    "{name} = {{ p50_us = {}, p99_us = {}, p999_us = {}, max_us = {} }}",
                    float(p.p50_us),
                    float(p.p99_us),
                    float(p.p999_us),
                    float(p.max_us)
                );
            }
        }
        for t in &self.trials {
            out.push('\n');
            write_trial_entry(&mut out, t);
        }
        out
    }

    /// Parses manifest text; `file` names it in errors.
    ///
    /// # Errors
    /// Any [`SessionError`] naming `file`, the line and the key.
    pub fn from_toml(text: &str, file: &Path) -> Result<Manifest, SessionError> {
        parse(text, file).map(|(m, _)| m)
    }

    /// The entry with trial id `id`.
    #[must_use]
    pub fn trial(&self, id: u32) -> Option<&TrialEntry> {
        self.trials.iter().find(|t| t.id == id)
    }
}
