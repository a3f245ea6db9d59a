//! The controller's end of the link: [`WireRig`] is a [`RigIo`], so the rig's own
//! `Controller` drives a remote plant without knowing it.
//!
//! `read(now)` takes every pending datagram from the transport, counts and drops the
//! bad, late and repeated ones ([`LinkCounters`]), and keeps the newest sensor frame by
//! sequence number. A transport error ends the drain and is returned (its `kind()`
//! says which, e.g. `Disconnected` for a refused port); frames taken before it are
//! kept. Otherwise it answers, in this order:
//! 1. a gap of more than `max_gap` consecutive lost frames in this read →
//!    [`WireError::GapTooLarge`] (`ErrorKind::Other`; the frame is still kept);
//! 2. no frame ever → [`WireError::NoFrameYet`] (`ErrorKind::Disconnected`);
//! 3. the newest frame arrived `stale_ticks` or more controller ticks ago →
//!    [`WireError::Stale`] (`ErrorKind::Timeout`). With one read per tick this is the
//!    `stale_ticks`-th consecutive read without a new frame; the reads before it return
//!    the newest frame again (zero-order hold);
//! 4. otherwise the newest frame, e-stop included (the controller trips on it).
//!
//! Staleness is judged on the controller's own clock; the two clocks are not assumed to
//! be synchronised (frames carry the plant's tick, which the command echoes back as
//! `answers_tick`).
//!
//! `write(now, command)` sends one command datagram stamped with `now`, the mode last
//! given to [`WireRig::set_mode`] and the plant tick of the newest frame. A non-finite
//! force is refused with an error and nothing is sent. A full socket buffer loses the
//! datagram (counted `unsent`; the plant's watchdog covers it) and is not an error. The
//! sequence number advances on every encoded command, so a local loss shows as a gap at
//! the plant.
//!
//! Start-up: the plant (clock master) sends frames to the controller it has learned
//! from a first command, so the controller writes before it can read; a zero command
//! in `Mode::Configured` is the hello. `read` returns `NoFrameYet` until a frame is in.
//!
//! Trials: commands carry the trial id given to [`WireRig::begin_trial`] (0 until
//! then). Once a trial is begun, a frame of another trial (the plant has not set the
//! new one up yet, or a late frame of the last) is a valid datagram, counted
//! `accepted`, but never the frame `read` returns: until the plant's frames name the
//! trial, `read` answers `NoFrameYet`. A controller at trial 0 takes every frame.
//!
//! Real time: all buffers are fields sized in [`WireRig::new`]; `read` and `write`
//! allocate nothing.

use rigtwin_device::{Mode, MotorCommand, RigIo, SensorFrame, Tick};

use crate::datagram::{CommandDatagram, Datagram, SensorDatagram};
use crate::error::WireError;
use crate::faults::MAX_DATAGRAM;
use crate::link::{Expect, Inbox, LinkCounters, check_stale_ticks, send_counted};
use crate::transport::Transport;

/// The controller end's limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RigLimits {
    /// Controller ticks without a new frame at which `read` times out (≥ 1). Default 4,
    /// 1 ms at 4 kHz.
    pub stale_ticks: u32,
    /// Most consecutive lost frames tolerated in one gap. Default 3: losing
    /// `stale_ticks` frames in a row is the same hazard as a timeout.
    pub max_gap: u32,
}

impl Default for RigLimits {
    fn default() -> RigLimits {
        RigLimits {
            stale_ticks: 4,
            max_gap: 3,
        }
    }
}

/// The controller's end of the link (module docs).
#[derive(Debug)]
pub struct WireRig<T: Transport> {
    transport: T,
    limits: RigLimits,
    inbox: Inbox,
    next_sequence: u32,
    trial: u16,
    mode: Mode,
    newest: Option<SensorDatagram>,
    newest_at: Tick,
    round_trip: Option<u64>,
    buf: [u8; MAX_DATAGRAM],
}

impl<T: Transport> WireRig<T> {
    /// The controller's end over `transport`; `stale_ticks` must be at least 1.
    pub fn new(transport: T, limits: RigLimits) -> Result<WireRig<T>, WireError> {
        check_stale_ticks(limits.stale_ticks)?;
        Ok(WireRig {
            transport,
            limits,
            inbox: Inbox::default(),
            next_sequence: 0,
            trial: 0,
            mode: Mode::Configured,
            newest: None,
            newest_at: Tick(0),
            round_trip: None,
            buf: [0; MAX_DATAGRAM],
        })
    }

    /// Sets the mode the next commands carry (the plant applies force only in `Active`).
    pub fn set_mode(&mut self, mode: Mode) {
        self.mode = mode;
    }

    /// Begins trial `trial` (1-based id): the next commands name it, and the frames of
    /// any other trial are no longer read (module docs). The newest frame is forgotten,
    /// so `read` answers `NoFrameYet` until the plant's first frame of this trial.
    pub fn begin_trial(&mut self, trial: u16) {
        self.trial = trial;
        self.newest = None;
        self.newest_at = Tick(0);
        self.round_trip = None;
    }

    /// The trial id the commands carry.
    #[must_use]
    pub fn trial(&self) -> u16 {
        self.trial
    }

    /// The controller's clock starts again at tick 0 (a trial's controller counts its
    /// own ticks from 0): the newest frame counts as arrived at tick 0, so the stale
    /// watchdog measures from there.
    pub fn restart_clock(&mut self) {
        self.newest_at = Tick(0);
    }

    /// The mode the next command carries.
    #[must_use]
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The limits in force.
    #[must_use]
    pub fn limits(&self) -> RigLimits {
        self.limits
    }

    /// What this end has received, accepted, rejected and sent.
    #[must_use]
    pub fn counters(&self) -> LinkCounters {
        self.inbox.counters
    }

    /// The newest accepted sensor frame with its plant tick, sequence number, the plant's
    /// watchdog flag and the echoed command tick.
    #[must_use]
    pub fn newest(&self) -> Option<&SensorDatagram> {
        self.newest.as_ref()
    }

    /// Controller ticks from sending a command to reading the first frame taken after the
    /// plant applied it, measured at the newest frame; `None` before any echo. In lock
    /// step it is 1.
    #[must_use]
    pub fn round_trip_ticks(&self) -> Option<u64> {
        self.round_trip
    }

    /// The transport.
    #[must_use]
    pub fn transport(&self) -> &T {
        &self.transport
    }

    /// The transport, e.g. to move a session clock on between trials.
    pub fn transport_mut(&mut self) -> &mut T {
        &mut self.transport
    }
}

impl<T: Transport> RigIo for WireRig<T> {
    type Error = WireError;

    fn read(&mut self, now: Tick) -> Result<SensorFrame, WireError> {
        let mut worst_gap = 0u32;
        let mut fresh = false;
        let drained = loop {
            match self.transport.try_recv(&mut self.buf) {
                Ok(Some(n)) => {
                    let bytes = self.buf.get(..n).unwrap_or(&[]);
                    if let Some((Datagram::Sensor(s), missing)) =
                        self.inbox.admit(bytes, Expect::Sensor)
                    {
                        worst_gap = worst_gap.max(missing);
                        if self.trial == 0 || s.trial == self.trial {
                            self.newest = Some(s);
                            fresh = true;
                        }
                    }
                }
                Ok(None) => break Ok(()),
                Err(e) => break Err(e),
            }
        };
        // Frames taken before a transport error still count as arrived now.
        if fresh {
            self.newest_at = now;
            if let Some(echo) = self.newest.and_then(|s| s.echo_tick) {
                self.round_trip = Some(now.0.saturating_sub(echo.0));
            }
        }
        drained?;
        if worst_gap > self.limits.max_gap {
            return Err(WireError::GapTooLarge {
                missing: worst_gap,
                limit: self.limits.max_gap,
            });
        }
        let newest = self.newest.ok_or(WireError::NoFrameYet)?;
        let age = now.0.saturating_sub(self.newest_at.0);
        if age >= u64::from(self.limits.stale_ticks) {
            return Err(WireError::Stale {
                ticks: age,
                limit: self.limits.stale_ticks,
            });
        }
        Ok(newest.frame)
    }

    fn write(&mut self, now: Tick, command: MotorCommand) -> Result<(), WireError> {
        let bytes = CommandDatagram {
            sequence: self.next_sequence,
            tick: now,
            trial: self.trial,
            command,
            mode: self.mode,
            answers_tick: self.newest.map(|s| s.tick),
        }
        .encode()?;
        self.next_sequence = self.next_sequence.wrapping_add(1);
        send_counted(&mut self.transport, &mut self.inbox.counters, now, &bytes)
    }
}
