#!/usr/bin/env python3
"""A lab's own controller in the loop: holds the handle of `rigtwin plant serve` with a
PD law, over the wire protocol of hil/docs/wire.md, using only the standard library.

    rigtwin plant serve reach-perturb --listen 127.0.0.1:47000 --max-trials 1
    python3 hil/examples/pd_client.py --plant 127.0.0.1:47000 --seconds 3

It names a trial (the plant sets it up: the simulated subject starts its reach), says
hello with zero commands in mode `configured`, then answers every sensor frame at once
with F = -Kp (x - x0) - Kd v in mode `active`, where x0 is where the handle was when
the first frame came in and v is the encoder position's difference per tick, low-pass
filtered. The subject pushes; the PD law holds. At the end it prints one line per fact
(frames, the largest deviation from x0, frames the plant flagged with its command
watchdog) and exits 0; it exits 1 if no frame came within --connect-timeout-s.
"""
import argparse
import math
import socket
import struct
import sys
import time

# The two datagrams of wire protocol version 1 (hil/docs/wire.md, "Python struct formats").
SENSOR = struct.Struct("<4sHHIQqqddBBHQ")  # 64 bytes, plant -> controller
COMMAND = struct.Struct("<4sHHIQddBxHQ")  # 48 bytes, controller -> plant
MAGIC, VERSION, KIND_SENSOR, KIND_COMMAND = b"RTWI", 1, 1, 2
NO_TICK = 2**64 - 1
MODE_CONFIGURED, MODE_ACTIVE = 0, 2
FLAG_WATCHDOG_ZEROED = 1
TICK_HZ = 4000.0


def parse_args():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--plant", required=True, help="HOST:PORT of `rigtwin plant serve`")
    p.add_argument("--seconds", type=float, default=3.0, help="how long to hold, s (default 3)")
    p.add_argument("--trial", type=int, default=1, help="trial id the plant sets up (default 1)")
    p.add_argument("--kp", type=float, default=10000.0, help="stiffness, N/m (default 10000)")
    p.add_argument("--kd", type=float, default=200.0, help="damping, N s/m (default 200)")
    p.add_argument("--quantum-m", type=float, default=1e-6, help="encoder quantum, m/count (default 1e-6)")
    p.add_argument("--hello-frames", type=int, default=8, help="frames answered in mode configured first")
    p.add_argument("--connect-timeout-s", type=float, default=5.0)
    a = p.parse_args()
    host, _, port = a.plant.rpartition(":")
    if not host or not port.isdigit():
        p.error(f"--plant {a.plant!r}: expected HOST:PORT")
    if not (0 <= a.trial <= 65535):
        p.error("--trial: 0 to 65535")
    return a, (host, int(port))


def main():
    args, plant = parse_args()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.connect(plant)
    seq = 0

    def send(tick, fx, fy, mode, answers):
        nonlocal seq
        sock.send(COMMAND.pack(MAGIC, VERSION, KIND_COMMAND, seq, tick, fx, fy, mode, args.trial, answers))
        seq = (seq + 1) & 0xFFFFFFFF

    # Hello until the plant's first frame of our trial arrives.
    sock.settimeout(0.001)
    deadline = time.monotonic() + args.connect_timeout_s
    tick = 0
    first = None
    while first is None:
        if time.monotonic() > deadline:
            print(f"no frame of trial {args.trial} from {args.plant} within {args.connect_timeout_s} s", file=sys.stderr)
            return 1
        send(tick, 0.0, 0.0, MODE_CONFIGURED, NO_TICK)
        tick += 1
        try:
            data = sock.recv(256)
        except (socket.timeout, ConnectionRefusedError):
            continue
        if len(data) == SENSOR.size:
            f = SENSOR.unpack(data)
            if f[0] == MAGIC and f[1] == VERSION and f[2] == KIND_SENSOR and f[11] == args.trial:
                first = f

    q = args.quantum_m
    x0 = (first[5] * q, first[6] * q)
    prev = x0
    v = [0.0, 0.0]
    alpha = 1.0 - math.exp(-2.0 * math.pi * 50.0 / TICK_HZ)  # 50 Hz low-pass on velocity
    frames, flagged, bad, max_dev = 0, 0, 0, 0.0
    newest_seq = None
    sock.settimeout(0.05)
    end = time.monotonic() + args.seconds
    while time.monotonic() < end:
        try:
            data = sock.recv(256)
        except socket.timeout:
            continue
        if len(data) != SENSOR.size:
            bad += 1
            continue
        f = SENSOR.unpack(data)
        if f[0] != MAGIC or f[1] != VERSION or f[2] != KIND_SENSOR:
            bad += 1
            continue
        s = f[3]
        if newest_seq is not None and ((s - newest_seq) & 0xFFFFFFFF) >= 2**31:
            continue  # late or repeated: never go back in time
        newest_seq = s
        frames += 1
        if f[10] & FLAG_WATCHDOG_ZEROED:
            flagged += 1
        x = (f[5] * q, f[6] * q)
        for a in range(2):
            v[a] += alpha * ((x[a] - prev[a]) * TICK_HZ - v[a])
        prev = x
        dev = math.hypot(x[0] - x0[0], x[1] - x0[1])
        max_dev = max(max_dev, dev)
        mode = MODE_CONFIGURED if frames <= args.hello_frames else MODE_ACTIVE
        fx = -args.kp * (x[0] - x0[0]) - args.kd * v[0]
        fy = -args.kp * (x[1] - x0[1]) - args.kd * v[1]
        if mode != MODE_ACTIVE:
            fx = fy = 0.0
        send(tick, fx, fy, mode, f[4])
        tick += 1
    print(f"frames {frames}")
    print(f"frames flagged by the plant's command watchdog {flagged}")
    print(f"bad datagrams {bad}")
    print(f"held at x0 = ({x0[0]:.4f}, {x0[1]:.4f}) m; largest deviation {max_dev * 1e3:.2f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
