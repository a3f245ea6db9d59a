//! What the wire costs per tick, against the 250 µs a 4 kHz tick leaves:
//! - `codec/*`: encode then decode one datagram (pure CPU);
//! - `udp_loopback/raw_pair`: one 64-byte datagram from socket A to socket B and a
//!   48-byte answer back, on 127.0.0.1, one thread, blocking sockets (kernel cost of a
//!   round trip, no scheduler wake-up);
//! - `udp_loopback/ends_round_trip`: the same through the crate — `PlantEnd::send_frame`,
//!   `WireRig::read`, `WireRig::write`, `PlantEnd::poll_command` — over non-blocking
//!   `UdpTransport`s, spinning on the receive (what a lock-step co-simulation pays).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::hint::black_box;
use std::net::UdpSocket;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use rigtwin_device::{Mode, MotorCommand, RigIo, SensorFrame, Tick};
use rigtwin_wire::{
    CommandDatagram, PlantEnd, PlantLimits, RigLimits, SensorDatagram, UdpTransport, WireRig,
    decode,
};

fn codec(c: &mut Criterion) {
    let s = SensorDatagram {
        sequence: 41,
        tick: Tick(123_456),
        trial: 7,
        frame: SensorFrame {
            encoder_counts: [-12_345, 67_890],
            force_raw_n: [1.25, -3.5],
            estop: false,
        },
        watchdog_zeroed: false,
        echo_tick: Some(Tick(123_455)),
    };
    let m = CommandDatagram {
        sequence: 40,
        tick: Tick(99),
        trial: 7,
        command: MotorCommand {
            force_n: [4.0, -2.0],
        },
        mode: Mode::Active,
        answers_tick: Some(Tick(123_456)),
    };
    c.bench_function("codec/sensor_encode_decode", |b| {
        b.iter(|| decode(&black_box(&s).encode()))
    });
    c.bench_function("codec/command_encode_decode", |b| {
        b.iter(|| decode(&black_box(&m).encode().unwrap()))
    });
}

fn udp(c: &mut Criterion) {
    let a = UdpSocket::bind("127.0.0.1:0").unwrap();
    let b = UdpSocket::bind("127.0.0.1:0").unwrap();
    a.connect(b.local_addr().unwrap()).unwrap();
    b.connect(a.local_addr().unwrap()).unwrap();
    for s in [&a, &b] {
        s.set_read_timeout(Some(Duration::from_secs(1))).unwrap();
    }
    let frame = [7u8; 64];
    let answer = [9u8; 48];
    let mut buf = [0u8; 256];
    let mut group = c.benchmark_group("udp_loopback");
    group.bench_function("raw_pair", |bench| {
        bench.iter(|| {
            a.send(&frame).unwrap();
            let n = b.recv(&mut buf).unwrap();
            b.send(&answer).unwrap();
            let m = a.recv(&mut buf).unwrap();
            black_box((n, m))
        })
    });

    let plant_side = UdpTransport::listen("127.0.0.1:0").unwrap();
    let plant_addr = plant_side.local_addr().unwrap();
    let controller_side = UdpTransport::connect("127.0.0.1:0", plant_addr).unwrap();
    let mut plant = PlantEnd::new(plant_side, PlantLimits::default()).unwrap();
    // A generous staleness limit: the spin below reads many times per "tick".
    let limits = RigLimits {
        stale_ticks: u32::MAX,
        max_gap: u32::MAX,
    };
    let mut rig = WireRig::new(controller_side, limits).unwrap();
    rig.set_mode(Mode::Active);
    // Hello: the plant learns its peer from the first command.
    rig.write(Tick(0), MotorCommand::ZERO).unwrap();
    spin(|| plant.poll_command(Tick(0)).unwrap().is_some());
    let mut n = 1u64;
    group.bench_function("ends_round_trip", |bench| {
        bench.iter(|| {
            let now = Tick(n);
            n += 1;
            plant.send_frame(now, SensorFrame::default()).unwrap();
            spin(|| rig.read(now).is_ok() && rig.newest().is_some_and(|s| s.tick == now));
            rig.write(
                now,
                MotorCommand {
                    force_n: [1.0, 2.0],
                },
            )
            .unwrap();
            spin(|| plant.poll_command(now).unwrap().is_some());
            black_box(plant.applied_force(now))
        })
    });
    group.finish();
}

/// Polls until `ready`, at most ten million times (seconds, far beyond a loopback hop).
fn spin(mut ready: impl FnMut() -> bool) {
    for _ in 0..10_000_000 {
        if ready() {
            return;
        }
        std::hint::spin_loop();
    }
    panic!("no datagram on loopback after 10 000 000 polls");
}

criterion_group!(benches, codec, udp);
criterion_main!(benches);
