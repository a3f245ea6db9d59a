#!/usr/bin/env python3
"""Writes the golden datagrams that tests/golden.rs compares the Rust codec against,
using only the `struct` formats printed in hil/docs/wire.md, so the doc's formats and
the crate's layout cannot drift apart. Run from this folder: python3 make_golden.py"""
import struct

SENSOR = struct.Struct("<4sHHIQqqddBBHQ")
COMMAND = struct.Struct("<4sHHIQddBxHQ")
NO_TICK = 2**64 - 1

vectors = {
    # magic, version, kind, sequence, tick, x_counts, y_counts, fx_raw, fy_raw, estop, flags, trial, echo_tick
    "sensor.hex": SENSOR.pack(b"RTWI", 1, 1, 4_294_967_295, 123_456_789, -120_000, 45, 0.8, -1.25e-3, 1, 1, 513, 123_456_700),
    "sensor_no_echo.hex": SENSOR.pack(b"RTWI", 1, 1, 0, 0, 0, 0, 0.0, 0.0, 0, 0, 0, NO_TICK),
    # magic, version, kind, sequence, tick, fx_n, fy_n, mode, trial, answers_tick
    "command.hex": COMMAND.pack(b"RTWI", 1, 2, 17, 9_000, 12.5, -3.0, 2, 42, 123_456_789),
    "command_hello.hex": COMMAND.pack(b"RTWI", 1, 2, 0, 0, 0.0, 0.0, 0, 0, NO_TICK),
}
for name, data in vectors.items():
    with open(name, "w") as f:
        f.write(data.hex() + "\n")
