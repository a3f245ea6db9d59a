//! The two ends over real UDP sockets on 127.0.0.1 (port 0 on both): start-up with the
//! plant learning its peer, a few hundred ticks in lock step, and a stranger's datagrams.
//! Every wait is a bounded poll with a wall-clock deadline, so a lost datagram fails the
//! test instead of hanging it.
#![allow(clippy::unwrap_used, clippy::expect_used)]
// Waiting for a datagram on loopback: a relative sleep between polls is what is meant.
#![allow(clippy::disallowed_methods)]

use std::net::UdpSocket;
use std::time::{Duration, Instant};

use rigtwin_device::{ErrorKind, Mode, MotorCommand, RigIo, RigIoError, SensorFrame, Tick};
use rigtwin_wire::{
    CommandDatagram, PlantEnd, PlantLimits, RigLimits, UdpTransport, WireError, WireRig,
};

/// Loopback delivers in microseconds; two seconds means something is broken.
const DEADLINE: Duration = Duration::from_secs(2);

fn wait_for(what: &str, mut ready: impl FnMut() -> bool) {
    let start = Instant::now();
    while !ready() {
        assert!(start.elapsed() < DEADLINE, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_micros(20));
    }
}

fn frame_at(n: u64) -> SensorFrame {
    SensorFrame {
        encoder_counts: [n as i64, 2 * n as i64],
        force_raw_n: [0.125 * n as f64, -1.0],
        estop: false,
    }
}

type Pair = (WireRig<UdpTransport>, PlantEnd<UdpTransport>);

fn pair() -> Pair {
    let plant_side = UdpTransport::listen("127.0.0.1:0").unwrap();
    let plant_addr = plant_side.local_addr().unwrap();
    let controller_side = UdpTransport::connect("127.0.0.1:0", plant_addr).unwrap();
    // Polling several times per tick keeps `now` fixed, so the limits never bite here;
    // they are tested in lock step over the channel pair.
    let rig = WireRig::new(controller_side, RigLimits::default()).unwrap();
    let plant = PlantEnd::new(plant_side, PlantLimits::default()).unwrap();
    (rig, plant)
}

#[test]
fn three_hundred_ticks_over_loopback_arrive_exactly_once_in_order() {
    let (mut rig, mut plant) = pair();
    // Before the hello the plant has no peer: its frame is not sent, and the controller
    // has nothing to read.
    plant.send_frame(Tick(0), frame_at(0)).unwrap();
    assert_eq!(plant.counters().unsent, 1);
    assert_eq!(rig.read(Tick(0)).unwrap_err(), WireError::NoFrameYet);
    // Hello: a zero command in Configured; the plant learns its peer from it.
    rig.write(Tick(0), MotorCommand::ZERO).unwrap();
    wait_for("the hello", || {
        plant.poll_command(Tick(0)).unwrap().is_some()
    });
    assert_eq!(
        plant.transport().peer(),
        Some(rig.transport().local_addr().unwrap())
    );
    rig.set_mode(Mode::Active);
    let ticks = 300u64;
    for n in 1..=ticks {
        let now = Tick(n);
        plant.send_frame(now, frame_at(n)).unwrap();
        wait_for("a frame", || {
            rig.read(now).is_ok() && rig.newest().is_some_and(|s| s.tick == now)
        });
        assert_eq!(rig.read(now).unwrap(), frame_at(n));
        let force_n = [n as f64, -(n as f64)];
        rig.write(now, MotorCommand { force_n }).unwrap();
        let mut got: Option<CommandDatagram> = None;
        wait_for("a command", || {
            got = plant.poll_command(now).unwrap();
            got.is_some()
        });
        let c = got.unwrap();
        assert_eq!(
            (c.tick, c.answers_tick, c.mode),
            (now, Some(now), Mode::Active)
        );
        assert_eq!(plant.applied_force(now), force_n);
    }
    let r = rig.counters();
    let p = plant.counters();
    // Plant: 1 unsent before the hello, then one frame per tick. Controller: the hello
    // plus one command per tick. Nothing rejected, nothing lost, in either direction.
    assert_eq!((p.sent, p.unsent), (ticks, 1));
    assert_eq!(
        (r.received, r.accepted, r.rejected(), r.lost),
        (ticks, ticks, 0, 0)
    );
    assert_eq!((r.sent, r.unsent), (ticks + 1, 0));
    assert_eq!(
        (p.received, p.accepted, p.rejected(), p.lost),
        (ticks + 1, ticks + 1, 0, 0)
    );
}

#[test]
fn a_stranger_cannot_become_the_peer_or_speak_after_it() {
    let (mut rig, mut plant) = pair();
    let plant_addr = plant.transport().local_addr().unwrap();
    let stranger = UdpSocket::bind("127.0.0.1:0").unwrap();
    // Garbage first: rejected, and its sender is not adopted.
    stranger.send_to(b"hello plant", plant_addr).unwrap();
    wait_for("the garbage", || {
        plant.poll_command(Tick(0)).unwrap();
        plant.counters().received == 1
    });
    assert_eq!(plant.counters().bad_magic, 1);
    assert_eq!(plant.transport().peer(), None);
    // The controller's hello makes it the peer.
    rig.write(Tick(0), MotorCommand::ZERO).unwrap();
    wait_for("the hello", || {
        plant.poll_command(Tick(0)).unwrap().is_some()
    });
    // A well-formed, newer command from the stranger is skipped by the transport.
    let forged = CommandDatagram {
        sequence: 1000,
        tick: Tick(5),
        trial: 0,
        command: MotorCommand {
            force_n: [50.0, 50.0],
        },
        mode: Mode::Active,
        answers_tick: None,
    };
    stranger
        .send_to(&forged.encode().unwrap(), plant_addr)
        .unwrap();
    wait_for("the forged command", || {
        plant.poll_command(Tick(1)).unwrap();
        plant.transport().foreign() == 1
    });
    assert_eq!(plant.counters().accepted, 1);
    assert_eq!(plant.applied_force(Tick(1)), [0.0; 2]);
}

#[test]
fn a_controller_without_a_plant_is_disconnected() {
    // Bind a port, then free it: nothing listens there. Linux reports the ICMP
    // port-unreachable on a connected socket as ConnectionRefused on a later call.
    let gone = UdpSocket::bind("127.0.0.1:0").unwrap();
    let addr = gone.local_addr().unwrap();
    drop(gone);
    let t = UdpTransport::connect("127.0.0.1:0", addr).unwrap();
    let mut rig = WireRig::new(t, RigLimits::default()).unwrap();
    let mut errors = Vec::new();
    let start = Instant::now();
    for n in 0..1000u64 {
        errors.extend(rig.write(Tick(n), MotorCommand::ZERO).err());
        errors.extend(rig.read(Tick(n)).err());
        if start.elapsed() > DEADLINE {
            break;
        }
        std::thread::sleep(Duration::from_micros(50));
    }
    // The socket itself reported the missing plant, and every failure, from the socket
    // or from the absent frames, says the plant is not there (not a timeout).
    assert!(
        errors.iter().any(|e| matches!(e, WireError::Transport(_))),
        "{errors:?}"
    );
    assert!(
        errors.iter().all(|e| e.kind() == ErrorKind::Disconnected),
        "{errors:?}"
    );
    assert_eq!(rig.counters().received, 0);
}
