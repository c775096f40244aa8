#!/usr/bin/env python3
"""Writes a data set with one forced case of N rows (512 Hz, two-frequency motion, linear
forces plus a deterministic sawtooth perturbation), the same signal as
tests/faults.rs::write_case_rows. Usage: long_case.py OUT_DIR N_ROWS"""
import math, os, sys

out, rows = sys.argv[1], int(sys.argv[2])
os.makedirs(os.path.join(out, "cases"), exist_ok=True)
with open(os.path.join(out, "manifest.toml"), "w") as f:
    f.write('''format = "aeroform-dataset/1"
name = "long case"

[section]
chord = 0.25
span = 0.75
air_density = 1.225

[units]
heave = "mm"
pitch = "deg"
lift = "N"
moment = "N*m"

[[case]]
id = "D-U6-A12"
kind = "forced"
file = "cases/D-U6-A12.csv"
wind_speed = 6.0
config = "D"
freq_pitch = 2.0
freq_heave = 1.3
''')
tau = 2 * math.pi
with open(os.path.join(out, "cases", "D-U6-A12.csv"), "w", buffering=1 << 20) as f:
    f.write("t,h,alpha,lift,moment\n")
    for i in range(rows):
        t = i / 512.0
        a = 12.0 * math.sin(tau * 2.0 * t)
        h = 18.0 * math.sin(tau * 1.3 * t)
        lift = -0.9 * a - 0.02 * h + 1e-3 * ((i * 7919) % 1000) / 1000.0
        moment = 0.03 * a + 0.001 * h
        f.write(f"{t!r},{h!r},{a!r},{lift!r},{moment!r}\n")
