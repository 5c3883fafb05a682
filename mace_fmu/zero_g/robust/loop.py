"""The loop a sweep closes: which FMU input the compensator drives, what it measures, the disturbance.

Default (as ``examples/cosimulate.py``): the secondary gimbal, MACE's disturbance source, slews in
a 0.5 deg square wave at 1 Hz (its Z servo's command) for the first period, then holds; the
payload rate gyro about Z measures; the primary gimbal's Z servo command is the control. Cost:
the RMS of the measured payload rate [V] over the run (the slew and the settling after it).
Stability: a growth test, since an FMU gives only its outputs. After the disturbance stops, a
stable loop's response dies out, the slowest closed-loop mode last, so the RMS falls from one
period to the next; a growing mode takes over and makes it rise. The loop is called unstable
when the RMS over the run's last period exceeds the RMS over the period before by more than
``growth_limit``, or an output is not finite. Growth is seen once the growing mode outweighs the
decaying response, and faster than ln(growth_limit) / period (0.049 /s for 1.05 and 1 s): with
the default design a loop whose spectral radius is 1.0013 (0.65 /s) shows it from the fourth
second on, hence 4 s of run; slower or later growth is missed (the state-space cross-check gives
the eigenvalues).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mace_fmu.errors import MaceError


@dataclass(frozen=True)
class LoopSpec:
    """Signals, disturbance and timing of the closed loop (volts at the FMU's boundary)."""

    control_input: str = "gimbal_primary_z"  #: FMU input the compensator drives [V]
    measurement: str = "gyro_payload_z"  #: FMU output the compensator reads, also the performance [V]
    disturbance_input: str = "gimbal_secondary_z"  #: FMU input the disturbance drives [V]
    disturbance_amplitude_v: float = 0.5  #: square wave +-amplitude [V] (1 V = 1 deg of gimbal command)
    disturbance_period_s: float = 1.0  #: also the length of the growth test's windows
    disturbance_periods: int = 1  #: periods of square wave from t = 0; then 0 V
    duration_s: float = 4.0  #: simulated time [s], whole periods, at least disturbance_periods + 2
    step_s: float = 0.002  #: communication step of the FMU and sample time of the compensator [s]
    growth_limit: float = 1.05  #: RMS of the last period / of the one before above this: unstable

    def __post_init__(self) -> None:
        periods = self.duration_s / self.disturbance_period_s
        steps = self.disturbance_period_s / self.step_s
        if not (self.step_s > 0 and abs(steps - round(steps)) < 1e-9 * steps and self.disturbance_periods >= 1
                and periods >= self.disturbance_periods + 2 - 1e-12
                and abs(periods - round(periods)) < 1e-9 * periods and self.growth_limit > 1.0):
            raise MaceError(f"loop timing: need whole steps per period, whole periods per run (>= the disturbance's + 2) and a growth "
                            f"limit > 1; got step {self.step_s} s, period {self.disturbance_period_s} s, duration "
                            f"{self.duration_s} s, growth limit {self.growth_limit}")

    @property
    def steps(self) -> int:
        """Communication steps per run."""
        return int(round(self.duration_s / self.step_s))

    @property
    def steps_per_period(self) -> int:
        return int(round(self.disturbance_period_s / self.step_s))

    def times_s(self) -> np.ndarray:
        """Sample times [s]: the start of each step."""
        return np.arange(self.steps) * self.step_s

    def disturbance(self) -> np.ndarray:
        """The square wave [V] held over each step: +amplitude in the first half of a period, -amplitude in the
        second, for ``disturbance_periods`` periods; then 0."""
        k = np.arange(self.steps)
        phase = k % self.steps_per_period
        wave = np.where(phase < self.steps_per_period // 2, self.disturbance_amplitude_v, -self.disturbance_amplitude_v)
        return np.where(k < self.disturbance_periods * self.steps_per_period, wave, 0.0)


@dataclass(frozen=True)
class LoopVerdict:
    """Cost and stability of one closed-loop response."""

    cost_rms_v: float  #: RMS of the measurement over the run [V]; inf if not finite
    growth_ratio: float  #: RMS of the last period / of the period before
    stable: bool


def judge(measurement_v: np.ndarray, loop: LoopSpec) -> LoopVerdict:
    """Cost and the growth test of one run's measurement samples (see the module docstring)."""
    y = np.asarray(measurement_v, dtype=float)
    if y.size != loop.steps or not np.all(np.isfinite(y)):
        return LoopVerdict(cost_rms_v=float("inf"), growth_ratio=float("inf"), stable=False)
    n = loop.steps_per_period
    last, before = np.sqrt(np.mean(y[-n:] ** 2)), np.sqrt(np.mean(y[-2 * n:-n] ** 2))
    ratio = float(last / before) if before > 0 else (1.0 if last == 0 else float("inf"))
    return LoopVerdict(cost_rms_v=float(np.sqrt(np.mean(y**2))), growth_ratio=ratio,
                       stable=bool(ratio <= loop.growth_limit))
