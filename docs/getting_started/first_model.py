# ---
# jupyter:
#   jupytext:
#     formats: py:percent,ipynb
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # First model: modes, a volts-volts model and its FMU
#
# This page is a script in cells (`first_model.py`) paired with a notebook (`first_model.ipynb`) by
# jupytext: open either in Jupyter, run `jupytext --sync docs/getting_started/first_model.py` after
# editing one of them. `tests/test_docs_commands.py` runs the script and checks that the pair agrees.
#
# The free (0-g) MACE structure, from the bundled NASTRAN deck to an FMU and back.

# %%
import tempfile

import control as ct
import fmpy
import numpy as np

from mace_fmu import ModelledElectronics, SignalSelection, compute_modes, export_fmu, volts_model
from mace_fmu.util.frequency import ZERO_HZ

# %% [markdown]
# The modes of the free structure up to 10 Hz, labelled by the structure file's components (rigid
# bodies and mechanisms, whose computed frequencies are round-off, read 0 Hz):

# %%
modes = compute_modes(configuration="0g", max_hz=10.0)
for f, label in zip(modes.frequencies_hz, modes.labels):
    print(f"{f if abs(f) >= ZERO_HZ else 0.0:8.3f} Hz  {label}")

# %% [markdown]
# A volts-volts model of one channel: the secondary Z gimbal command (1 V = 1 deg, servos closed) to
# the payload Z rate gyro [V], modes up to 10 Hz, the Bessel filters as their equivalent delay.

# %%
model = volts_model(modes, electronics=ModelledElectronics(bessel="delay"),
                    signals=SignalSelection(inputs=["gimbal_secondary_z"], outputs=["gyro_payload_z"]))
print(model.system.nstates, "states;", model.electronics.describe())

# %% [markdown]
# Its FMU (native, FMI 2.0 co-simulation), stepped by fmpy on a 1 V step, against python-control's
# exact zero-order hold of the same state space:

# %%
folder = tempfile.mkdtemp()
fmu = export_fmu(model, out_dir=folder, name="first_model")
t = np.arange(0.0, 2.0 + 1e-12, 2e-3)
step = np.zeros(len(t), dtype=[("time", float), ("gimbal_secondary_z", float)])
step["time"], step["gimbal_secondary_z"] = t, 1.0
run = fmpy.simulate_fmu(str(fmu), input=step, output=["gyro_payload_z"], step_size=2e-3, output_interval=2e-3,
                        stop_time=t[-1])
reference = ct.forced_response(ct.sample_system(model.system, 2e-3, "zoh"), T=t, U=np.ones((1, len(t)))).outputs
difference = np.max(np.abs(run["gyro_payload_z"][:len(t)] - reference)) / np.ptp(reference)
print(f"FMU against the exact zero-order hold: {difference:.1e} of the response's range")
