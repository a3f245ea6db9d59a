#!/usr/bin/env python3
"""Writes signal_golden.json: reference outputs of scipy/numpy for the Rust signal module.

Run from anywhere:  python3 device/tests/golden/make_golden.py
Needs numpy and scipy (pip install numpy scipy). CI does not run this script; it
only reads the committed JSON. Every signal is deterministic (fixed seed, closed
forms), so re-running reproduces the file up to the scipy version recorded in it.

Besides scipy's own outputs, Savitzky-Golay cases carry weights computed exactly in
rational arithmetic (fractions.Fraction), because scipy solves an unscaled
Vandermonde least-squares problem that loses digits for long windows; the tests
use the exact weights to separate our error from scipy's.
"""

import json
import math
import os
import sys
from fractions import Fraction

import numpy as np
import scipy
from scipy import integrate, signal

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "signal_golden.json")
rng = np.random.default_rng(20261122)


def arr(x):
    return [float(v) for v in np.asarray(x, dtype=float).ravel()]


# ---------------------------------------------------------------- signals
def min_jerk_reach(fs, duration_s, move_s=0.6, dist_m=0.1):
    """Minimum-jerk reach of dist_m in move_s, a 150 ms raised-cosine bump of 5 mm
    (the shape a force pulse leaves on position) from 0.3 s, quantised to 1 um."""
    t = np.arange(int(round(duration_s * fs))) / fs
    tau = np.clip(t / move_s, 0.0, 1.0)
    x = dist_m * (10 * tau**3 - 15 * tau**4 + 6 * tau**5)
    pulse = (t >= 0.3) & (t < 0.45)
    x = x + np.where(pulse, 0.005 * 0.5 * (1 - np.cos(2 * np.pi * (t - 0.3) / 0.15)), 0.0)
    return np.round(x / 1e-6) * 1e-6


signals = {
    "noise600": rng.standard_normal(600),
    "chirp1k": signal.chirp(np.arange(1000) / 1000.0, f0=1.0, t1=1.0, f1=200.0, method="linear"),
    "reach4k": min_jerk_reach(4000.0, 0.75),
    "reach1k": min_jerk_reach(1000.0, 1.0),
    "reach250": min_jerk_reach(250.0, 3.0),
}
signals["short7"] = signals["noise600"][:7].copy()
signals["short3"] = signals["noise600"][10:13].copy()
signals["short19"] = signals["noise600"][20:39].copy()  # padlen 18 + 1 for a 5th-order sosfiltfilt
signals["short13"] = signals["noise600"][40:53].copy()  # padlen 12 + 1 for a 3rd-order filtfilt
signals["short2"] = signals["noise600"][60:62].copy()


# ---------------------------------------------------------------- Savitzky-Golay
def exact_weights(window, polyorder, deriv, pos):
    """Dot-order weights of the derivative at `pos` (samples from window start) of
    the least-squares polynomial through `window` samples, in exact arithmetic,
    per unit sample spacing."""
    if deriv > polyorder:
        return [Fraction(0)] * window
    xs = [Fraction(j) for j in range(window)]
    n = polyorder + 1
    g = [[sum(x ** (i + k) for x in xs) for k in range(n)] for i in range(n)]
    rhs = [Fraction(0)] * n
    for k in range(deriv, n):
        rhs[k] = Fraction(math.factorial(k), math.factorial(k - deriv)) * Fraction(pos) ** (k - deriv)
    # Gauss-Jordan on the exact Gram matrix.
    m = [row[:] + [r] for row, r in zip(g, rhs)]
    for c in range(n):
        piv = next(r for r in range(c, n) if m[r][c] != 0)
        m[c], m[piv] = m[piv], m[c]
        inv = 1 / m[c][c]
        m[c] = [v * inv for v in m[c]]
        for r in range(n):
            if r != c and m[r][c] != 0:
                f = m[r][c]
                m[r] = [a - f * b for a, b in zip(m[r], m[c])]
    lam = [m[i][n] for i in range(n)]
    return [sum(lam[k] * x**k for k in range(n)) for x in xs]


def exact_savgol(x, window, polyorder, deriv, delta, mode, cval):
    """Savitzky-Golay output with exact weights and fsum dot products."""
    half = window // 2
    n = len(x)
    scale = delta**deriv
    centre = [float(w) / scale for w in exact_weights(window, polyorder, deriv, half)]
    y = np.zeros(n)
    if mode == "interp":
        for i in range(half, n - half):
            y[i] = math.fsum(w * v for w, v in zip(centre, x[i - half : i + half + 1]))
        for i in range(half):
            wl = [float(w) / scale for w in exact_weights(window, polyorder, deriv, i)]
            y[i] = math.fsum(w * v for w, v in zip(wl, x[:window]))
            pos = window - half + i
            wr = [float(w) / scale for w in exact_weights(window, polyorder, deriv, pos)]
            y[n - half + i] = math.fsum(w * v for w, v in zip(wr, x[n - window :]))
    else:
        pad = {"nearest": "edge", "mirror": "reflect", "wrap": "wrap", "constant": "constant"}[mode]
        reps = window // max(n, 1) + 2
        kw = {"constant_values": cval} if mode == "constant" else {}
        # np.pad 'reflect' == ndimage 'mirror'; pad in steps so long pads repeat correctly.
        xp = np.asarray(x, dtype=float)
        padded = xp
        done = 0
        while done < half:
            step = min(half - done, len(xp) - 1 if pad == "reflect" else len(xp)) or 1
            padded = np.pad(padded, step, mode=pad, **kw) if pad != "reflect" or len(xp) > 1 else np.pad(padded, step, mode="edge")
            done += step
        off = done - half
        for i in range(n):
            seg = padded[off + i : off + i + window]
            y[i] = math.fsum(w * v for w, v in zip(centre, seg))
    return y


savgol_cases = []


def add_savgol(sig, window, polyorder, deriv, delta, mode, cval=0.0, exact=True):
    x = signals[sig]
    c = signal.savgol_coeffs(window, polyorder, deriv=deriv, delta=delta)
    y = signal.savgol_filter(x, window, polyorder, deriv=deriv, delta=delta, mode=mode, cval=cval)
    case = {
        "signal": sig, "window": window, "polyorder": polyorder, "deriv": deriv,
        "delta": delta, "mode": mode, "cval": cval,
        "coeffs": arr(c),
        "coeffs_exact": arr([float(w) / delta**deriv for w in exact_weights(window, polyorder, deriv, window // 2)][::-1]),
        "y": arr(y),
    }
    if exact:
        case["y_exact"] = arr(exact_savgol(x, window, polyorder, deriv, delta, mode, cval))
    savgol_cases.append(case)


for mode, cval in [("interp", 0.0), ("nearest", 0.0), ("mirror", 0.0), ("constant", 0.5), ("wrap", 0.0)]:
    add_savgol("noise600", 5, 2, 0, 1.0, mode, cval)
    add_savgol("noise600", 11, 3, 1, 0.01, mode, cval)
add_savgol("chirp1k", 21, 4, 2, 0.001, "interp")
add_savgol("chirp1k", 21, 4, 2, 0.001, "mirror")
# Seed settings (windows from Schafer's formula, see savgol_cutoff.rs).
for d in range(4):
    add_savgol("reach4k", 253, 5, d, 1 / 4000, "interp")  # Borner: order 5, 30 Hz at 4 kHz
for d in range(2):
    add_savgol("reach1k", 67, 5, d, 1 / 1000, "interp")  # order 5, 30 Hz at 1 kHz
for d in range(3):
    add_savgol("reach250", 27, 6, d, 1 / 250, "interp")  # Piovesan: order 6, 23.4 Hz at 250 Hz
# Short signals: exactly one window; windows longer than the signal.
add_savgol("short7", 7, 3, 0, 1.0, "interp")
add_savgol("short7", 7, 3, 1, 1.0, "interp")
for mode in ["nearest", "mirror", "wrap"]:
    add_savgol("short3", 7, 2, 0, 1.0, mode)
add_savgol("short3", 7, 2, 0, 1.0, "constant", -1.0)
add_savgol("noise600", 1, 0, 0, 1.0, "interp")  # identity
add_savgol("noise600", 7, 2, 3, 1.0, "interp")  # deriv > polyorder: zeros

windows_for_cutoff = [
    {"polyorder": n, "cutoff_hz": fc, "fs_hz": fs}
    for (n, fc, fs) in [(5, 30.0, 4000.0), (5, 30.0, 1000.0), (6, 23.4, 250.0)]
]

# ---------------------------------------------------------------- Butterworth
butter_cases = []
for order in range(1, 9):
    for kind in ["lowpass", "highpass"]:
        for fc, fs in [(1.0, 4000.0), (30.0, 1000.0), (10.0, 250.0), (110.0, 250.0)]:
            sos = signal.butter(order, fc, btype=kind, fs=fs, output="sos")
            butter_cases.append({"order": order, "kind": kind, "cutoff_hz": [fc], "fs_hz": fs, "sos": arr(sos)})
for order in range(1, 5):
    for lo, hi, fs in [(5.0, 50.0, 1000.0), (0.5, 20.0, 4000.0)]:
        sos = signal.butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos")
        butter_cases.append({"order": order, "kind": "bandpass", "cutoff_hz": [lo, hi], "fs_hz": fs, "sos": arr(sos)})

sosfiltfilt_cases = []
for sig, order, fc, fs, kind in [
    ("reach4k", 5, 1.0, 4000.0, "highpass"),  # Borner's estimator filter
    ("reach4k", 5, 1.0, 4000.0, "lowpass"),
    ("chirp1k", 4, 30.0, 1000.0, "lowpass"),
    ("reach250", 2, 10.0, 250.0, "lowpass"),
    ("noise600", 3, 50.0, 1000.0, "highpass"),
    ("noise600", 1, 50.0, 1000.0, "lowpass"),
    ("short19", 5, 1.0, 4000.0, "highpass"),
]:
    sos = signal.butter(order, fc, btype=kind, fs=fs, output="sos")
    x = signals[sig]
    sosfiltfilt_cases.append({
        "signal": sig, "order": order, "cutoff_hz": fc, "fs_hz": fs, "kind": kind,
        "sos": arr(sos), "zi": arr(signal.sosfilt_zi(sos)),
        "sosfilt": arr(signal.sosfilt(sos, x)), "y": arr(signal.sosfiltfilt(sos, x)),
    })

filtfilt_cases = []
for sig, b, a in [
    ("chirp1k", *signal.butter(4, 30.0, fs=1000.0)),
    ("noise600", *signal.butter(2, 5.0, btype="highpass", fs=1000.0)),
    ("noise600", *signal.butter(1, 100.0, fs=1000.0)),
    ("reach250", [1 / 3, 1 / 3, 1 / 3], [1.0]),
    ("noise600", [0.5, 0.2], [2.0, -0.6, 0.1]),  # a0 != 1, len(b) < len(a)
    ("short13", *signal.butter(3, 100.0, fs=1000.0)),
]:
    x = signals[sig]
    filtfilt_cases.append({
        "signal": sig, "b": arr(b), "a": arr(a), "zi": arr(signal.lfilter_zi(b, a)),
        "lfilter": arr(signal.lfilter(b, a, x)), "y": arr(signal.filtfilt(b, a, x)),
    })

welch_cases = []
for sig, fs, nperseg in [
    ("noise600", 1000.0, 64), ("noise600", 1000.0, 128), ("noise600", 1000.0, 255),
    ("noise600", 1000.0, 600), ("chirp1k", 1000.0, 256), ("reach4k", 4000.0, 1024),
    ("short7", 100.0, 7), ("short7", 100.0, 2),
]:
    f, p = signal.welch(signals[sig], fs=fs, nperseg=nperseg)
    welch_cases.append({"signal": sig, "fs_hz": fs, "nperseg": nperseg, "freq_hz": arr(f), "density": arr(p)})

calculus_cases = []
for sig, dt in [("noise600", 0.001), ("chirp1k", 0.001), ("reach4k", 1 / 4000), ("short2", 0.5), ("short3", 0.1)]:
    y = signals[sig]
    calculus_cases.append({
        "signal": sig, "dt_s": dt,
        "cumulative_trapezoid": arr(integrate.cumulative_trapezoid(y, dx=dt, initial=0)),
        "gradient": arr(np.gradient(y, dt)),
    })

out = {
    "generator": "device/tests/golden/make_golden.py",
    "versions": {"python": sys.version.split()[0], "numpy": np.__version__, "scipy": scipy.__version__},
    "signals": {k: arr(v) for k, v in signals.items()},
    "savgol": savgol_cases,
    "savgol_window_for_cutoff": windows_for_cutoff,
    "butter": butter_cases,
    "sosfiltfilt": sosfiltfilt_cases,
    "filtfilt": filtfilt_cases,
    "welch": welch_cases,
    "calculus": calculus_cases,
}
with open(OUT, "w") as fh:
    json.dump(out, fh, separators=(",", ":"))
print(f"wrote {OUT}: {os.path.getsize(OUT) / 1e6:.2f} MB")
