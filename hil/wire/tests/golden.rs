//! The crate's encoder against datagrams packed by Python's `struct` with the format
//! strings printed in `hil/docs/wire.md` (`tests/golden/make_golden.py` wrote the
//! `.hex` files): byte-identical both ways, so the spec a lab reads and the code agree.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rigtwin_device::{Mode, MotorCommand, SensorFrame, Tick};
use rigtwin_wire::{CommandDatagram, Datagram, SensorDatagram, decode};

fn golden(name: &str) -> Vec<u8> {
    let path = format!("{}/tests/golden/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let hex = text.trim();
    (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
        .collect()
}

fn check(name: &str, d: Datagram) {
    let bytes = golden(name);
    let ours = match d {
        Datagram::Sensor(s) => s.encode().to_vec(),
        Datagram::Command(c) => c.encode().unwrap().to_vec(),
    };
    assert_eq!(ours, bytes, "{name}: encode");
    assert_eq!(decode(&bytes), Ok(d), "{name}: decode");
}

#[test]
fn python_struct_and_the_crate_agree_byte_for_byte() {
    check(
        "sensor.hex",
        Datagram::Sensor(SensorDatagram {
            sequence: u32::MAX,
            tick: Tick(123_456_789),
            trial: 513,
            frame: SensorFrame {
                encoder_counts: [-120_000, 45],
                force_raw_n: [0.8, -1.25e-3],
                estop: true,
            },
            watchdog_zeroed: true,
            echo_tick: Some(Tick(123_456_700)),
        }),
    );
    check(
        "sensor_no_echo.hex",
        Datagram::Sensor(SensorDatagram::default()),
    );
    check(
        "command.hex",
        Datagram::Command(CommandDatagram {
            sequence: 17,
            tick: Tick(9_000),
            trial: 42,
            command: MotorCommand {
                force_n: [12.5, -3.0],
            },
            mode: Mode::Active,
            answers_tick: Some(Tick(123_456_789)),
        }),
    );
    check(
        "command_hello.hex",
        Datagram::Command(CommandDatagram {
            sequence: 0,
            tick: Tick(0),
            trial: 0,
            command: MotorCommand::ZERO,
            mode: Mode::Configured,
            answers_tick: None,
        }),
    );
}
