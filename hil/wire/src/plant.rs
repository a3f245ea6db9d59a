//! The plant's end of the link: [`PlantEnd`] receives motor commands, holds the newest
//! (zero-order hold), watches that they keep coming, and sends sensor frames.
//!
//! The plant is the clock master: once per plant tick it calls, in this order,
//! [`PlantEnd::poll_command`], [`PlantEnd::applied_force`] (the force to put on the
//! motors for this tick), steps its physics, and [`PlantEnd::send_frame`].
//!
//! Command watchdog: if the newest valid command arrived `stale_ticks` or more plant
//! ticks ago (with one poll per tick: the `stale_ticks`-th consecutive poll without a new
//! command), the applied force is zero and every frame sent says so (flags bit 0). It
//! is not latched: a fresh command is applied again, because the controller has its
//! own latched safety layer and sees the flag. Before the first command, and whenever
//! the newest command's mode is not `Active`, the applied force is zero too (without
//! the flag).
//!
//! A listening UDP transport learns its peer from the first valid command; frames sent
//! before that are counted `unsent`.
//!
//! Trials: every frame carries the trial id set by [`PlantEnd::set_trial`] (0 until
//! then); a plant that runs a protocol reads the trial the controller asks for from
//! [`PlantEnd::latest_command`] and sets it up before saying so.
//!
//! Real time: all buffers are fields sized in [`PlantEnd::new`]; nothing here allocates
//! after it.

use rigtwin_device::{Mode, SensorFrame, Tick};

use crate::datagram::{CommandDatagram, Datagram, SensorDatagram};
use crate::error::WireError;
use crate::faults::MAX_DATAGRAM;
use crate::link::{Expect, Inbox, LinkCounters, check_stale_ticks, send_counted};
use crate::transport::Transport;

/// The plant end's limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlantLimits {
    /// Plant ticks without a new command at which the force is zeroed (≥ 1). Default 4,
    /// 1 ms at 4 kHz.
    pub stale_ticks: u32,
}

impl Default for PlantLimits {
    fn default() -> PlantLimits {
        PlantLimits { stale_ticks: 4 }
    }
}

/// The plant's end of the link (module docs).
#[derive(Debug)]
pub struct PlantEnd<T: Transport> {
    transport: T,
    limits: PlantLimits,
    inbox: Inbox,
    next_sequence: u32,
    trial: u16,
    latest: Option<CommandDatagram>,
    latest_at: Tick,
    buf: [u8; MAX_DATAGRAM],
}

impl<T: Transport> PlantEnd<T> {
    /// The plant's end over `transport`; `stale_ticks` must be at least 1.
    pub fn new(transport: T, limits: PlantLimits) -> Result<PlantEnd<T>, WireError> {
        check_stale_ticks(limits.stale_ticks)?;
        Ok(PlantEnd {
            transport,
            limits,
            inbox: Inbox::default(),
            next_sequence: 0,
            trial: 0,
            latest: None,
            latest_at: Tick(0),
            buf: [0; MAX_DATAGRAM],
        })
    }

    /// Takes every pending datagram at plant tick `now`; returns the newest command that
    /// arrived in this poll, `None` if none did. On a transport error the commands taken
    /// before it are kept.
    pub fn poll_command(&mut self, now: Tick) -> Result<Option<CommandDatagram>, WireError> {
        let mut fresh = None;
        while let Some(n) = self.transport.try_recv(&mut self.buf)? {
            let bytes = self.buf.get(..n).unwrap_or(&[]);
            if let Some((Datagram::Command(c), _)) = self.inbox.admit(bytes, Expect::Command) {
                self.transport.accept_peer();
                self.latest = Some(c);
                self.latest_at = now;
                fresh = Some(c);
            }
        }
        Ok(fresh)
    }

    /// `true` when commands have stopped: the newest arrived `stale_ticks` or more plant
    /// ticks before `now`. `false` before the first command.
    #[must_use]
    pub fn watchdog_zeroed(&self, now: Tick) -> bool {
        self.latest.is_some()
            && now.0.saturating_sub(self.latest_at.0) >= u64::from(self.limits.stale_ticks)
    }

    /// The force to apply at plant tick `now`, N per axis: the newest command's, held;
    /// zero before the first command, when the watchdog has fired, or when the
    /// command's mode is not `Active`.
    #[must_use]
    pub fn applied_force(&self, now: Tick) -> [f64; 2] {
        match self.latest {
            Some(c) if c.mode == Mode::Active && !self.watchdog_zeroed(now) => c.command.force_n,
            _ => [0.0; 2],
        }
    }

    /// The trial id the next frames carry: the trial this plant has set up (0: none).
    pub fn set_trial(&mut self, trial: u16) {
        self.trial = trial;
    }

    /// The trial id the frames carry.
    #[must_use]
    pub fn trial(&self) -> u16 {
        self.trial
    }

    /// The newest valid command, if any.
    #[must_use]
    pub fn latest_command(&self) -> Option<&CommandDatagram> {
        self.latest.as_ref()
    }

    /// Sends the sensor frame sampled at plant tick `now`, with the watchdog flag and the
    /// tick of the newest command. A full buffer or a peer not yet known loses the frame
    /// (counted `unsent`) without an error.
    pub fn send_frame(&mut self, now: Tick, frame: SensorFrame) -> Result<(), WireError> {
        let bytes = SensorDatagram {
            sequence: self.next_sequence,
            tick: now,
            trial: self.trial,
            frame,
            watchdog_zeroed: self.watchdog_zeroed(now),
            echo_tick: self.latest.map(|c| c.tick),
        }
        .encode();
        self.next_sequence = self.next_sequence.wrapping_add(1);
        send_counted(&mut self.transport, &mut self.inbox.counters, now, &bytes)
    }

    /// What this end has received, accepted, rejected and sent.
    #[must_use]
    pub fn counters(&self) -> LinkCounters {
        self.inbox.counters
    }

    /// The limits in force.
    #[must_use]
    pub fn limits(&self) -> PlantLimits {
        self.limits
    }

    /// The transport.
    #[must_use]
    pub fn transport(&self) -> &T {
        &self.transport
    }
}
