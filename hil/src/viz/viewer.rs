//! The viewer: turns trials, arm trajectories, ellipses and events into rerun chunks.

use std::collections::BTreeSet;

use rerun::external::re_log_types::{ApplicationId, StoreId, StoreKind};
use rerun::log::{Chunk, ChunkComponents, RowId, TimeColumn};
use rerun::{
    Arrows2D, AsComponents, Boxes2D, Color, LineStrips2D, Points2D, Scalars,
    SerializedComponentColumn, SeriesLines, TextLog, TimePoint, Timeline,
};

use super::columns::{
    ArmColumns, EventLevel, RigGeometry, Stamp, TrialColumns, TrialMeta, TrialSpan, tick_of,
};
use super::geometry::{
    EllipseAxes, RESPONSE_WINDOW_S, ellipse_axes, ellipse_outline, variational_response,
};
use super::ids::IdSource;
use super::sink::Sink;
use super::target::Target;
use super::{VizError, blueprint, paths};

/// Highest sample rate sent to a live viewer by default, Hz; files get every sample.
pub const DEFAULT_LIVE_RATE_HZ: f64 = 500.0;

/// Colour of an ellipse drawn by [`Viewer::log_ellipse`].
const ELLIPSE_RGB: [u8; 3] = [170, 60, 170];

/// Points on an ellipse outline.
const ELLIPSE_SEGMENTS: usize = 128;

const TIMELINE_TICK: &str = "tick";
const TIMELINE_TIME: &str = "time";
const TIMELINE_TRIAL: &str = "trial";

/// Streams a session to rerun: a live viewer, an `.rrd` file, or a buffer.
///
/// Every method sends whole columns (rerun's columnar path, one chunk per entity per call),
/// never row by row. Chunks are numbered by a counter, the store is stamped with a fixed
/// source and the given recording id, and nothing reads the clock, so saving the same calls
/// twice gives the same messages, byte for byte; only the order of the two stores' manifests
/// in the file's footer is rerun's `HashMap` order.
#[derive(Debug)]
pub struct Viewer {
    store_id: StoreId,
    sink: Sink,
    ids: IdSource,
    live_rate_hz: f64,
    next_offset_s: f64,
    geometry: RigGeometry,
    styled: BTreeSet<String>,
    shoulder_logged: bool,
}

/// One row of time stamps per sample sent.
struct Times {
    tick: Vec<i64>,
    time_s: Vec<f64>,
    trial: Option<Vec<i64>>,
}

impl Times {
    fn of(stamps: &[Stamp]) -> Self {
        Self {
            tick: stamps.iter().map(|s| s.tick).collect(),
            time_s: stamps.iter().map(|s| s.time_s).collect(),
            trial: stamps
                .iter()
                .map(|s| s.trial.map(i64::from))
                .collect::<Option<Vec<_>>>(),
        }
    }

    fn columns(&self) -> Vec<TimeColumn> {
        let mut out = vec![
            TimeColumn::new_sequence(TIMELINE_TICK, self.tick.iter().copied()),
            TimeColumn::new_duration_secs(TIMELINE_TIME, self.time_s.iter().copied()),
        ];
        if let Some(trial) = &self.trial {
            out.push(TimeColumn::new_sequence(
                TIMELINE_TRIAL,
                trial.iter().copied(),
            ));
        }
        out
    }
}

fn f32_point(x: f64, y: f64) -> [f32; 2] {
    [x as f32, y as f32]
}

fn level_name(level: EventLevel) -> &'static str {
    match level {
        EventLevel::Info => rerun::TextLogLevel::INFO,
        EventLevel::Warn => rerun::TextLogLevel::WARN,
        EventLevel::Error => rerun::TextLogLevel::ERROR,
    }
}

/// Colours of the x and y lines of a series.
const XY_RGB: [[u8; 3]; 2] = [[230, 85, 60], [50, 120, 220]];

/// Colours of the wake-up latency and the held share.
const TIMING_RGB: [[u8; 3]; 2] = [[90, 90, 90], [220, 60, 160]];

/// Colours of the shoulder and elbow angles.
const ARM_ANGLES_RGB: [[u8; 3]; 2] = [[120, 90, 200], [60, 170, 120]];

/// Colours of the six muscles: each antagonist pair (flexor, extensor) one hue, the
/// flexor darker.
const MUSCLE_RGB: [[u8; 3]; paths::MUSCLES] = [
    [200, 60, 40],
    [240, 150, 120],
    [40, 90, 200],
    [130, 170, 240],
    [40, 150, 70],
    [130, 210, 140],
];

/// How long a viewer at a `connect` address has to accept a connection. The rerun SDK
/// connects lazily and, with nobody listening, its sender blocks for good once its buffer
/// fills; asking first turns that into an error after this long.
pub const CONNECT_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(3);

/// Checks that something accepts TCP connections at the proxy URL's host and port.
fn check_viewer_answers(url: &str) -> Result<(), VizError> {
    use std::net::ToSocketAddrs as _;
    let no = |reason: String| VizError::NoViewer {
        url: url.to_owned(),
        reason,
    };
    let host_port = url
        .split_once("://")
        .map_or(url, |(_, rest)| rest)
        .split('/')
        .next()
        .unwrap_or("");
    let addrs: Vec<_> = host_port
        .to_socket_addrs()
        .map_err(|e| no(format!("cannot resolve {host_port}: {e}")))?
        .collect();
    let mut last = format!("{host_port} resolves to no address");
    for addr in addrs {
        match std::net::TcpStream::connect_timeout(&addr, CONNECT_TIMEOUT) {
            Ok(_) => return Ok(()),
            Err(e) => last = format!("{addr}: {e}"),
        }
    }
    Err(no(last))
}

fn positive(what: &'static str, value: f64) -> Result<f64, VizError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(VizError::NotPositive { what, value })
    }
}

impl Viewer {
    /// Opens the target and sends the layout. `app_id` groups recordings in the viewer;
    /// `recording_id` names this one and should be derived from the session (the same session
    /// then replaces itself in a viewer, and files are reproducible).
    pub fn new(target: &Target, app_id: &str, recording_id: &str) -> Result<Self, VizError> {
        let store_id = store_id(app_id, recording_id)?;
        let sink = match target {
            Target::Save(path) => Sink::file(path.clone())?,
            Target::Spawn => Sink::Live(stream_builder(&store_id).spawn()?),
            Target::Connect(url) => {
                check_viewer_answers(url)?;
                Sink::Live(stream_builder(&store_id).connect_grpc_opts(url.clone())?)
            }
        };
        Self::with_sink(sink, store_id)
    }

    /// A viewer that encodes into memory; [`Self::finish`] returns the `.rrd` bytes. For tests
    /// and benchmarks.
    pub fn in_memory(app_id: &str, recording_id: &str) -> Result<Self, VizError> {
        let store_id = store_id(app_id, recording_id)?;
        Self::with_sink(Sink::memory()?, store_id)
    }

    fn with_sink(mut sink: Sink, store_id: StoreId) -> Result<Self, VizError> {
        let mut ids = IdSource::default();
        if !sink.is_live() {
            sink.open_store(&store_id, ids.message())?;
        }
        let (messages, activation) = blueprint::messages(&store_id, &mut ids)?;
        sink.send_blueprint(messages, activation)?;
        Ok(Self {
            store_id,
            sink,
            ids,
            live_rate_hz: DEFAULT_LIVE_RATE_HZ,
            next_offset_s: 0.0,
            geometry: RigGeometry::with_workspace(0.15),
            styled: BTreeSet::new(),
            shoulder_logged: false,
        })
    }

    /// The highest sample rate sent to a live viewer (files always get every sample).
    pub fn set_live_rate_hz(&mut self, hz: f64) -> Result<(), VizError> {
        self.live_rate_hz = positive("live rate (Hz)", hz)?;
        Ok(())
    }

    /// Every how many samples one is sent, at this sampling rate.
    /// The rows of a trial a series sends (every row, or thinned to the live rate) and their
    /// times; `None` for an empty trial.
    fn picks(&self, span: &TrialSpan, t_s: &[f64]) -> Option<(Vec<usize>, Times)> {
        let n = t_s.len();
        if n == 0 {
            return None;
        }
        let rate_hz = if span.duration_s > 0.0 {
            n as f64 / span.duration_s
        } else {
            1.0
        };
        let picks: Vec<usize> = (0..n).step_by(self.stride(rate_hz)).collect();
        let stamps: Vec<Stamp> = picks.iter().map(|&i| span.stamp(t_s[i])).collect();
        let times = Times::of(&stamps);
        Some((picks, times))
    }

    fn stride(&self, rate_hz: f64) -> usize {
        if self.sink.is_live() && rate_hz > self.live_rate_hz {
            (rate_hz / self.live_rate_hz).floor().max(1.0) as usize
        } else {
            1
        }
    }

    /// Draws the static rig: workspace limits, the lower cart's rail, the carts' sizes and the
    /// shoulder. Call once before the trials (otherwise a 0.15 m workspace is assumed).
    pub fn log_rig_geometry(&mut self, geometry: &RigGeometry) -> Result<(), VizError> {
        let w = positive("workspace half width (m)", geometry.workspace_half_width_m)?;
        self.geometry = geometry.clone();
        let square = vec![
            f32_point(-w, -w),
            f32_point(w, -w),
            f32_point(w, w),
            f32_point(-w, w),
            f32_point(-w, -w),
        ];
        self.send_static(
            paths::WORKSPACE,
            &LineStrips2D::new([square])
                .with_colors([Color::from_rgb(150, 150, 150)])
                .with_labels(["workspace"]),
        )?;
        let rail = geometry.lower_rail_y_m;
        let reach = w + geometry.lower_cart_half_size_m[0];
        self.send_static(
            paths::RAIL_X,
            &LineStrips2D::new([[f32_point(-reach, rail), f32_point(reach, rail)]])
                .with_colors([Color::from_rgb(90, 90, 90)]),
        )?;
        // The carriage's sizes and colours, once: per sample only the centres are sent.
        let [lx, ly] = geometry.lower_cart_half_size_m;
        let [ux, uy] = geometry.upper_cart_half_size_m;
        self.send_static(
            paths::CARRIAGE,
            &Boxes2D::update_fields()
                .with_half_sizes([f32_point(lx, ly), f32_point(ux, uy)])
                .with_colors([Color::from_rgb(200, 160, 60), Color::from_rgb(220, 120, 40)]),
        )?;
        self.send_static(
            paths::CARRIAGE,
            &LineStrips2D::update_fields().with_colors([Color::from_rgb(90, 90, 90)]),
        )?;
        self.send_static(
            paths::CARRIAGE,
            &Points2D::update_fields()
                .with_radii([0.008f32])
                .with_colors([Color::from_rgb(30, 30, 30)]),
        )?;
        if let Some(shoulder) = geometry.shoulder_m {
            self.log_shoulder(shoulder)?;
        }
        Ok(())
    }

    fn log_shoulder(&mut self, shoulder: [f64; 2]) -> Result<(), VizError> {
        self.shoulder_logged = true;
        self.send_static(
            paths::SHOULDER,
            &Points2D::new([f32_point(shoulder[0], shoulder[1])])
                .with_radii([0.015f32])
                .with_colors([Color::from_rgb(60, 120, 200)])
                .with_labels(["shoulder"]),
        )
    }

    /// Logs one trial: the carts, rail and handle animated over the trial, one time series
    /// per column, the hand path, start and goal, and for a perturbed trial the onset, the
    /// pulse's direction and the variational response over 150 ms.
    ///
    /// Trials are laid end to end on the `tick` and `time` timelines in the order they are
    /// logged. Returns where this one landed, for [`Self::log_arm`] and [`Self::log_ellipse`].
    pub fn log_trial(
        &mut self,
        meta: &TrialMeta,
        columns: &TrialColumns<'_>,
    ) -> Result<TrialSpan, VizError> {
        let rate_hz = positive("rate_hz", meta.rate_hz)?;
        columns.check()?;
        let n = columns.len();
        let span = TrialSpan {
            trial_index: meta.trial_index,
            offset_s: self.next_offset_s,
            duration_s: n as f64 / rate_hz,
        };
        self.next_offset_s += span.duration_s;
        if n == 0 {
            return Ok(span);
        }
        let stride = self.stride(rate_hz);
        let picks: Vec<usize> = (0..n).step_by(stride).collect();
        let stamps: Vec<Stamp> = picks.iter().map(|&i| span.stamp(columns.t_s[i])).collect();
        let times = Times::of(&stamps);
        let (x, y) = (columns.x_m, columns.y_m);

        // The carriage: both carts' centres (lower, upper), the upper cart's rail and the
        // handle, one row per sample on one set of timeline columns.
        let rail_y = self.geometry.lower_rail_y_m;
        let top = self.geometry.workspace_half_width_m + self.geometry.upper_cart_half_size_m[1];
        let hand: Vec<[f32; 2]> = picks.iter().map(|&i| f32_point(x[i], y[i])).collect();
        let centers = picks
            .iter()
            .flat_map(|&i| [f32_point(x[i], rail_y), f32_point(x[i], y[i])]);
        let rails: Vec<[[f32; 2]; 2]> = picks
            .iter()
            .map(|&i| [f32_point(x[i], rail_y), f32_point(x[i], top)])
            .collect();
        let rows = picks.len();
        let mut carriage = serialized(
            paths::CARRIAGE,
            Boxes2D::update_fields()
                .with_centers(centers)
                .columns(std::iter::repeat_n(2, rows)),
        )?;
        carriage.extend(serialized(
            paths::CARRIAGE,
            LineStrips2D::update_fields()
                .with_strips(rails)
                .columns_of_unit_batches(),
        )?);
        carriage.extend(serialized(
            paths::CARRIAGE,
            Points2D::update_fields()
                .with_positions(hand)
                .columns_of_unit_batches(),
        )?);
        self.send_components(paths::CARRIAGE, Some(&times), carriage)?;

        let pairs = [
            (paths::POSITION, Some(x), Some(y)),
            (paths::FORCE_SENSOR, Some(columns.fx_n), Some(columns.fy_n)),
            (
                paths::FORCE_PERT,
                Some(columns.pert_fx_n),
                Some(columns.pert_fy_n),
            ),
            (paths::VELOCITY, columns.vx_m_per_s, columns.vy_m_per_s),
            (paths::REFERENCE, columns.ref_x_m, columns.ref_y_m),
            (paths::COMMAND, columns.cmd_fx_n, columns.cmd_fy_n),
        ];
        for (path, a, b) in pairs {
            if a.is_none() && b.is_none() {
                continue;
            }
            // A lone x or y column keeps its place in the row; the other line is NaN (no
            // points drawn), so the entity always has the same two named lines.
            let at = |c: Option<&[f64]>, i: usize| c.map_or(f64::NAN, |c| c[i]);
            let values = picks.iter().flat_map(|&i| [at(a, i), at(b, i)]);
            self.send_series(path, paths::XY, XY_RGB, &times, values)?;
        }

        self.log_trial_overlay(meta, columns, &span)?;
        Ok(span)
    }

    /// The per-trial pictures, stamped at the trial's start.
    fn log_trial_overlay(
        &mut self,
        meta: &TrialMeta,
        columns: &TrialColumns<'_>,
        span: &TrialSpan,
    ) -> Result<(), VizError> {
        let start = span.stamp(columns.t_s.first().copied().unwrap_or(0.0));
        let (x, y) = (columns.x_m, columns.y_m);
        let path: Vec<[f32; 2]> = x.iter().zip(y).map(|(&x, &y)| f32_point(x, y)).collect();
        self.send_row(
            paths::TRIAL_PATH,
            start,
            &LineStrips2D::new([path])
                .with_labels([format!("trial {}", meta.id)])
                .with_colors([Color::from_rgb(100, 100, 100)]),
        )?;
        let targets: Vec<[f32; 2]> = [meta.start_m, meta.goal_m]
            .into_iter()
            .flatten()
            .map(|p| f32_point(p[0], p[1]))
            .collect();
        self.send_row(
            paths::TRIAL_TARGETS,
            start,
            &Points2D::new(targets)
                .with_radii([0.01f32])
                .with_colors([Color::from_rgb(40, 160, 80)]),
        )?;

        let mut text = format!("trial {} ({})", meta.id, meta.kind);
        let response = meta.perturbation.and_then(|p| {
            variational_response(columns.t_s, x, y, p.onset_s, RESPONSE_WINDOW_S).map(|r| (p, r))
        });
        match response {
            Some((p, r)) => {
                text.push_str(&format!(
                    ", perturbed {:.0} deg {} at {:.4} s",
                    p.angle_deg,
                    p.size.label(),
                    p.onset_s
                ));
                let at = [x[r.first], y[r.first]];
                let onset = span.stamp(p.onset_s);
                self.send_row(
                    paths::TRIAL_ONSET,
                    start,
                    &Points2D::new([f32_point(at[0], at[1])])
                        .with_radii([0.006f32])
                        .with_colors([Color::from_rgb(220, 40, 40)])
                        .with_labels([format!("onset {:.0}°", p.angle_deg)]),
                )?;
                let (c, s) = (
                    p.angle_deg.to_radians().cos(),
                    p.angle_deg.to_radians().sin(),
                );
                let len = p.size.arrow_m();
                self.send_row(
                    paths::TRIAL_PERTURBATION,
                    start,
                    &Arrows2D::from_vectors([f32_point(len * c, len * s)])
                        .with_origins([f32_point(at[0], at[1])])
                        .with_colors([Color::from_rgb(220, 40, 40)])
                        .with_labels([p.size.label()]),
                )?;
                let stamps: Vec<Stamp> = r.t_s.iter().map(|&t| span.stamp(t)).collect();
                let times = Times::of(&stamps);
                self.send_series(
                    paths::RESPONSE_X,
                    ["x"],
                    [XY_RGB[0]],
                    &times,
                    r.dx_m.iter().map(|d| d * 1e3),
                )?;
                self.send_series(
                    paths::RESPONSE_Y,
                    ["y"],
                    [XY_RGB[1]],
                    &times,
                    r.dy_m.iter().map(|d| d * 1e3),
                )?;
                self.log_event(
                    onset,
                    EventLevel::Info,
                    &format!("trial {}: perturbation onset", meta.id),
                )?;
            }
            None => {
                self.send_row(paths::TRIAL_ONSET, start, &Points2D::clear_fields())?;
                self.send_row(paths::TRIAL_PERTURBATION, start, &Arrows2D::clear_fields())?;
            }
        }
        self.log_event(start, EventLevel::Info, &text)
    }

    /// Logs the arm over a trial: upper arm and forearm as a polyline animated with the
    /// handle, the elbow, and both joint angles as time series (degrees).
    ///
    /// `t_s` is the trial's time column (the one given to [`Self::log_trial`]).
    pub fn log_arm(
        &mut self,
        span: &TrialSpan,
        t_s: &[f64],
        arm: &ArmColumns<'_>,
    ) -> Result<(), VizError> {
        arm.check(t_s.len())?;
        if !self.shoulder_logged {
            self.log_shoulder(arm.shoulder_m)?;
        }
        let Some((picks, times)) = self.picks(span, t_s) else {
            return Ok(());
        };
        let s = arm.shoulder_m;
        let links: Vec<[[f32; 2]; 3]> = picks
            .iter()
            .map(|&i| {
                [
                    f32_point(s[0], s[1]),
                    f32_point(arm.elbow_x_m[i], arm.elbow_y_m[i]),
                    f32_point(arm.hand_x_m[i], arm.hand_y_m[i]),
                ]
            })
            .collect();
        if self.styled.insert(paths::ARM_LINKS.to_owned()) {
            self.send_static(
                paths::ARM_LINKS,
                &LineStrips2D::update_fields()
                    .with_colors([Color::from_rgb(60, 120, 200)])
                    .with_radii([0.006f32]),
            )?;
            self.send_static(
                paths::ARM_LINKS,
                &Points2D::update_fields()
                    .with_colors([Color::from_rgb(60, 120, 200)])
                    .with_radii([0.01f32]),
            )?;
        }
        let elbow: Vec<[f32; 2]> = picks
            .iter()
            .map(|&i| f32_point(arm.elbow_x_m[i], arm.elbow_y_m[i]))
            .collect();
        let mut pose = serialized(
            paths::ARM_LINKS,
            LineStrips2D::update_fields()
                .with_strips(links)
                .columns_of_unit_batches(),
        )?;
        pose.extend(serialized(
            paths::ARM_LINKS,
            Points2D::update_fields()
                .with_positions(elbow)
                .columns_of_unit_batches(),
        )?);
        self.send_components(paths::ARM_LINKS, Some(&times), pose)?;
        let angles_deg = picks.iter().flat_map(|&i| {
            [
                arm.shoulder_rad[i].to_degrees(),
                arm.elbow_rad[i].to_degrees(),
            ]
        });
        self.send_series(
            paths::ARM_ANGLES_DEG,
            paths::ARM_ANGLE_NAMES,
            ARM_ANGLES_RGB,
            &times,
            angles_deg,
        )
    }

    /// Logs the arm's six muscle activations over a trial (N, one row of six per sample, in
    /// the order of [`paths::MUSCLE_NAMES`]) as one entity with six named lines,
    /// [`paths::MUSCLE_ACTIVATIONS_N`]. `t_s` is the trial's time column (the one given to
    /// [`Self::log_trial`]); a live viewer gets them thinned like the trial's series.
    pub fn log_activations(
        &mut self,
        span: &TrialSpan,
        t_s: &[f64],
        activations_n: &[[f64; paths::MUSCLES]],
    ) -> Result<(), VizError> {
        if activations_n.len() != t_s.len() {
            return Err(VizError::ColumnLength {
                column: "activations_n",
                len: activations_n.len(),
                expected: t_s.len(),
            });
        }
        let Some((picks, times)) = self.picks(span, t_s) else {
            return Ok(());
        };
        self.send_series(
            paths::MUSCLE_ACTIVATIONS_N,
            paths::MUSCLE_NAMES,
            MUSCLE_RGB,
            &times,
            picks.iter().flat_map(|&i| activations_n[i]),
        )
    }

    /// Logs a real-time loop's timing over a trial (per sample: the mean wake-up latency of
    /// the ticks run, µs, and the share of ticks held) as [`paths::TIMING_WAKE_US`] and
    /// [`paths::TIMING_HELD`]. `t_s` is the trial's time column.
    pub fn log_timing(
        &mut self,
        span: &TrialSpan,
        t_s: &[f64],
        timing: &[[f64; 2]],
    ) -> Result<(), VizError> {
        if timing.len() != t_s.len() {
            return Err(VizError::ColumnLength {
                column: "timing",
                len: timing.len(),
                expected: t_s.len(),
            });
        }
        let Some((picks, times)) = self.picks(span, t_s) else {
            return Ok(());
        };
        for (k, path) in [paths::TIMING_WAKE_US, paths::TIMING_HELD]
            .into_iter()
            .enumerate()
        {
            self.send_series(
                path,
                [path.rsplit('/').next().unwrap_or(path)],
                [TIMING_RGB[k]],
                &times,
                picks.iter().map(|&i| timing[i][k]),
            )?;
        }
        Ok(())
    }

    /// Draws a 2x2 matrix `m` (row-major; a stiffness `K` in N/m, a damping `D` in N s/m) as
    /// the image of the unit circle, `scale` metres per unit of `m`, centred at `center` (the
    /// hand position, m), with its principal semi-axes as arrows. `label` names the matrix and
    /// its unit; the values are appended. Static when `at` is `None`.
    ///
    /// Entities `ellipses/<name>/outline` and `ellipses/<name>/axes`. Returns the axes drawn
    /// (in the units of `m`, before scaling).
    pub fn log_ellipse(
        &mut self,
        name: &str,
        at: Option<Stamp>,
        center: [f64; 2],
        m: [[f64; 2]; 2],
        scale: f64,
        label: &str,
    ) -> Result<EllipseAxes, VizError> {
        self.log_ellipse_rgb(name, at, center, m, scale, label, ELLIPSE_RGB)
    }

    /// [`Self::log_ellipse`] in the colour `rgb` (e.g. an estimate and the ground truth side
    /// by side).
    #[allow(clippy::too_many_arguments)]
    pub fn log_ellipse_rgb(
        &mut self,
        name: &str,
        at: Option<Stamp>,
        center: [f64; 2],
        m: [[f64; 2]; 2],
        scale: f64,
        label: &str,
        rgb: [u8; 3],
    ) -> Result<EllipseAxes, VizError> {
        let color = Color::from_rgb(rgb[0], rgb[1], rgb[2]);
        let scale = positive("ellipse scale", scale)?;
        if name.trim().is_empty() {
            return Err(VizError::InvalidId {
                id: name.to_owned(),
                reason: "an ellipse needs a name".to_owned(),
            });
        }
        let axes = ellipse_axes(m);
        let outline: Vec<[f32; 2]> = ellipse_outline(center, m, scale, ELLIPSE_SEGMENTS)
            .into_iter()
            .map(|p| f32_point(p[0], p[1]))
            .collect();
        let text = format!(
            "{label} [[{:.1}, {:.1}], [{:.1}, {:.1}]]",
            m[0][0], m[0][1], m[1][0], m[1][1]
        );
        let outline_arch = LineStrips2D::new([outline])
            .with_labels([text])
            .with_colors([color]);
        let vectors: Vec<[f32; 2]> = (0..2)
            .map(|k| {
                let l = scale * axes.lengths[k];
                f32_point(l * axes.directions[k][0], l * axes.directions[k][1])
            })
            .collect();
        let axes_arch = Arrows2D::from_vectors(vectors)
            .with_origins([f32_point(center[0], center[1]); 2])
            .with_labels([
                format!("{:.1}", axes.lengths[0]),
                format!("{:.1}", axes.lengths[1]),
            ])
            .with_colors([color]);
        let (outline_path, axes_path) = (paths::ellipse_outline(name), paths::ellipse_axes(name));
        match at {
            Some(stamp) => {
                self.send_row(&outline_path, stamp, &outline_arch)?;
                self.send_row(&axes_path, stamp, &axes_arch)?;
            }
            None => {
                self.send_static(&outline_path, &outline_arch)?;
                self.send_static(&axes_path, &axes_arch)?;
            }
        }
        Ok(axes)
    }

    /// The four entries of a 2x2 matrix `m` (row-major) as one row of four scalars at `at`,
    /// one plotted line per entry named by `names` (`K11`, `K12`, `K21`, `K22`). The values
    /// are stored as `f64`, exactly as given (the outline and arrows of an ellipse are `f32`).
    pub fn log_matrix(
        &mut self,
        path: &'static str,
        at: Stamp,
        names: [&str; 4],
        m: [[f64; 2]; 2],
    ) -> Result<(), VizError> {
        if self.styled.insert(path.to_owned()) {
            self.send_static(path, &SeriesLines::new().with_names(names))?;
        }
        self.send_row(
            path,
            at,
            &Scalars::new([m[0][0], m[0][1], m[1][0], m[1][1]]),
        )
    }

    /// A text entry in the event log (safety events, protocol steps).
    pub fn log_event(&mut self, at: Stamp, level: EventLevel, text: &str) -> Result<(), VizError> {
        self.send_row(
            paths::EVENTS,
            at,
            &TextLog::new(text).with_level(level_name(level)),
        )
    }

    /// Ends the stream: writes the `.rrd` footer, or waits for a live viewer to take the
    /// data. Returns the bytes when the viewer was made with [`Self::in_memory`].
    pub fn finish(self) -> Result<Option<Vec<u8>>, VizError> {
        self.sink.finish()
    }

    /// The stamp at which a trial logged next would start.
    pub fn next_trial_offset_s(&self) -> f64 {
        self.next_offset_s
    }

    /// Lays the next trial no earlier than `offset_s` (session time, s): for callers that
    /// log a trial's series themselves with [`Self::log_series`] on a span they built.
    pub fn skip_to_offset_s(&mut self, offset_s: f64) {
        if offset_s.is_finite() && offset_s > self.next_offset_s {
            self.next_offset_s = offset_s;
        }
    }

    /// The stamp of a session time (trial unknown).
    pub fn stamp_at(&self, time_s: f64) -> Stamp {
        Stamp {
            tick: tick_of(time_s),
            time_s,
            trial: None,
        }
    }

    /// Logs one series of a trial at any entity path (overlays: `measured/…`, `simulated/…`):
    /// `values[i]` at trial time `t_s[i]` (increasing; thinned for a live viewer as in
    /// [`Self::log_trial`], at the mean rate of `t_s`). `name` is the legend and `rgb` the colour, both set the first
    /// time a path is logged. `span` is where the trial landed (from [`Self::log_trial`], or
    /// built by the caller to lay several series on the same trial).
    pub fn log_series(
        &mut self,
        path: &str,
        name: &str,
        rgb: [u8; 3],
        span: &TrialSpan,
        t_s: &[f64],
        values: &[f64],
    ) -> Result<(), VizError> {
        if values.len() != t_s.len() {
            return Err(VizError::ColumnLength {
                column: "values",
                len: values.len(),
                expected: t_s.len(),
            });
        }
        if path.trim().is_empty() {
            return Err(VizError::InvalidId {
                id: path.to_owned(),
                reason: "a series needs an entity path".to_owned(),
            });
        }
        let n = t_s.len();
        let stride = match (t_s.first(), t_s.last()) {
            (Some(a), Some(b)) if n > 1 && b > a => self.stride((n - 1) as f64 / (b - a)),
            _ => 1,
        };
        let picks: Vec<usize> = (0..n).step_by(stride).collect();
        let stamps: Vec<Stamp> = picks.iter().map(|&i| span.stamp(t_s[i])).collect();
        let times = Times::of(&stamps);
        self.send_series(
            path,
            [name],
            [rgb],
            &times,
            picks.iter().map(|&i| values[i]),
        )
    }

    /// Sends `W` scalars per row (`values` row after row, one row per entry of `times`),
    /// one plotted line per scalar named by `names`; the names and colours go out once, as
    /// static rows.
    fn send_series<const W: usize>(
        &mut self,
        path: &str,
        names: [&str; W],
        rgb: [[u8; 3]; W],
        times: &Times,
        values: impl Iterator<Item = f64>,
    ) -> Result<(), VizError> {
        if self.styled.insert(path.to_owned()) {
            self.send_static(
                path,
                &SeriesLines::new()
                    .with_names(names)
                    .with_colors(rgb.map(|[r, g, b]| Color::from_rgb(r, g, b))),
            )?;
        }
        let rows = times.tick.len();
        self.send_columns(
            path,
            Some(times),
            Scalars::new(values).columns(std::iter::repeat_n(W, rows)),
        )
    }

    fn send_columns<I>(
        &mut self,
        path: &str,
        times: Option<&Times>,
        columns: Result<I, rerun::SerializationError>,
    ) -> Result<(), VizError>
    where
        I: Iterator<Item = SerializedComponentColumn>,
    {
        let columns = serialized(path, columns)?;
        self.send_components(path, times, columns)
    }

    /// One chunk of `path`: the component columns (of one or several archetypes) on one set
    /// of timeline columns.
    fn send_components(
        &mut self,
        path: &str,
        times: Option<&Times>,
        columns: Vec<SerializedComponentColumn>,
    ) -> Result<(), VizError> {
        let timelines = times
            .map(Times::columns)
            .unwrap_or_default()
            .into_iter()
            .map(|c| (*c.timeline().name(), c))
            .collect();
        let components: ChunkComponents = columns.into_iter().collect();
        let chunk = Chunk::from_auto_row_ids(self.ids.chunk(), path.into(), timelines, components)
            .map_err(|source| VizError::Chunk {
                entity: path.to_owned(),
                source,
            })?;
        self.sink.send(&self.store_id, chunk)
    }

    fn send_row(&mut self, path: &str, at: Stamp, arch: &dyn AsComponents) -> Result<(), VizError> {
        let mut timepoint = TimePoint::from([
            (Timeline::new_sequence(TIMELINE_TICK), at.tick),
            (
                Timeline::new_duration(TIMELINE_TIME),
                (at.time_s * 1e9).round() as i64,
            ),
        ]);
        if let Some(trial) = at.trial {
            timepoint = timepoint.with(Timeline::new_sequence(TIMELINE_TRIAL), i64::from(trial));
        }
        self.send_built(path, timepoint, arch)
    }

    fn send_static(&mut self, path: &str, arch: &dyn AsComponents) -> Result<(), VizError> {
        self.send_built(path, TimePoint::default(), arch)
    }

    fn send_built(
        &mut self,
        path: &str,
        timepoint: TimePoint,
        arch: &dyn AsComponents,
    ) -> Result<(), VizError> {
        let id = self.ids.chunk();
        let chunk = Chunk::builder_with_id(id, path)
            .with_archetype(RowId::from_tuid(id.as_tuid().next()), timepoint, arch)
            .build()
            .map_err(|source| VizError::Chunk {
                entity: path.to_owned(),
                source,
            })?;
        self.sink.send(&self.store_id, chunk)
    }
}

/// The serialized columns of an archetype, or an error naming the entity.
fn serialized<I>(
    path: &str,
    columns: Result<I, rerun::SerializationError>,
) -> Result<Vec<SerializedComponentColumn>, VizError>
where
    I: Iterator<Item = SerializedComponentColumn>,
{
    columns
        .map(Iterator::collect)
        .map_err(|source| VizError::Serialize {
            entity: path.to_owned(),
            source,
        })
}

fn store_id(app_id: &str, recording_id: &str) -> Result<StoreId, VizError> {
    let app = ApplicationId::try_new(app_id).map_err(|err| VizError::InvalidId {
        id: app_id.to_owned(),
        reason: err.to_string(),
    })?;
    if recording_id.trim().is_empty() {
        return Err(VizError::InvalidId {
            id: recording_id.to_owned(),
            reason: "the recording id is empty".to_owned(),
        });
    }
    Ok(StoreId::new(StoreKind::Recording, app, recording_id))
}

fn stream_builder(store_id: &StoreId) -> rerun::RecordingStreamBuilder {
    rerun::RecordingStreamBuilder::from_store_id(store_id).send_properties(false)
}
