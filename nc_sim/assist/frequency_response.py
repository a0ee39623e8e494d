"""Frequency response of an axis' drive and mechanics, measured as a drive's own tools do
(TwinCAT TE5960, SINAMICS): an excitation goes into the drive at its own rate while the NC
holds the axis (or moves it at an offset speed, so friction does not dominate at standstill),
the drive trace records the response, and H1 = Pxy/Pxx with Welch averaging and the
coherence give the Bode plot (nc_sim/plant/frf.py).

What is measured, from which signals of the drive trace:

- mechanics: motor torque -> motor speed (excited at the torque setpoint);
- closed speed loop: speed setpoint -> motor speed (excited at the speed setpoint);
- open speed loop: speed error -> motor speed (the same excitation: speed = open loop · error);
- closed position loop: position command -> actual position, at the NC's cycle (excited at the
  position controller's command).

The analysis uses only what a real measurement has: the recorded signals, the drive's rate
and its torque limit; never the simulated mechanics' hidden parameters.
"""

from __future__ import annotations

import math
from collections.abc import Generator
from dataclasses import dataclass

import numpy as np

from nc_sim.assist.drive_axis import drive_axis
from nc_sim.assist.procedure import Procedure, Wait, on_copy
from nc_sim.assist.result import ExperimentError, Figure, Result, Series
from nc_sim.commands import Accepted, Move, Refused, Reset
from nc_sim.config import MachineConfig
from nc_sim.kernel import layout as L
from nc_sim.machine.machine import Machine
from nc_sim.plant import frf
from nc_sim.plant import layout as PL
from nc_sim.plant.tuning import loop_figures
from nc_sim.snapshot import AxisState
from nc_sim.units import MM_MIN_PER_MM_S, RPM_TO_RAD_S

MECHANICS, CLOSED_SPEED, OPEN_SPEED, CLOSED_POSITION = 1, 2, 3, 4
MEASUREMENTS = {
    MECHANICS: "mechanics (torque -> motor speed)",
    CLOSED_SPEED: "closed speed loop",
    OPEN_SPEED: "open speed loop",
    CLOSED_POSITION: "closed position loop",
}
PRBS, CHIRP = 1, 2
MAX_PLOT_POINTS = 600  # per curve, spaced evenly in log f
LEAD_IN_S = 0.2  # excitation before the recording counts: the loops settle into it
CHUNK_CYCLES = 50  # the position window is checked this often
SETTLE_S = 2.0  # back at the start: how long the lag may take to come into the window
MAX_SEGMENT = 1 << 16  # samples per average


def frequency_response_experiment(
    cfg: MachineConfig,
    axis: str,
    measurement: int = MECHANICS,
    excitation: int = PRBS,
    torque_pct: float = 2.0,
    speed_rpm: float = 20.0,
    position_mm: float = 0.1,
    offset_rpm: float = 30.0,
    f_min_hz: float = 5.0,
    f_max_hz: float | None = None,
    averages: int = 10,
    window_mm: float = 50.0,
) -> Result:
    """`frequency_response` on a fresh copy of the machine `cfg` describes."""
    return on_copy(
        cfg,
        lambda m: frequency_response(
            m,
            axis,
            measurement,
            excitation,
            torque_pct,
            speed_rpm,
            position_mm,
            offset_rpm,
            f_min_hz,
            f_max_hz,
            averages,
            window_mm,
        ),
    )


def _segment(fs_hz: float, f_min_hz: float, excitation: int) -> tuple[int, int]:
    """(samples per average, PRBS order): a PRBS period of 2**order - 1 samples, or a
    sweep, long enough to resolve f_min (at least four bins below it)."""
    need = min(MAX_SEGMENT, max(256, math.ceil(4.0 * fs_hz / f_min_hz)))
    order = max(8, math.ceil(math.log2(need + 1)))
    return (2**order - 1 if excitation == PRBS else 2**order), order


def _excitation(
    kind: int, order: int, nseg: int, count: int, fs_hz: float, f_lo: float, f_hi: float
) -> np.ndarray:
    """`count` samples of whole PRBS periods or whole sweeps of `nseg` samples, amplitude 1."""
    periods = math.ceil(count / nseg)
    if kind == PRBS:
        one = frf.prbs(order, 1.0, 1)
    else:
        one = frf.chirp(f_lo, f_hi, nseg / fs_hz, fs_hz, 1.0)
    return np.tile(one, periods)[:count]


@dataclass(frozen=True)
class Measured:
    """What one measurement found: the response over its band, how often the motor
    reversed meanwhile (per s) and how long the excitation ran (machine time)."""

    axis: str
    measurement: int
    h: frf.Frf
    reversals_per_s: float
    measured_s: float


def frequency_response(
    m: Machine,
    axis: str,
    measurement: int = MECHANICS,
    excitation: int = PRBS,
    torque_pct: float = 2.0,
    speed_rpm: float = 20.0,
    position_mm: float = 0.1,
    offset_rpm: float = 30.0,
    f_min_hz: float = 5.0,
    f_max_hz: float | None = None,
    averages: int = 10,
    window_mm: float = 50.0,
) -> Procedure:
    """`measure`, read as an engineer reads it: resonances, margins, bandwidth, the Bode plot."""
    done = yield from measure(
        m,
        axis,
        measurement,
        excitation,
        torque_pct,
        speed_rpm,
        position_mm,
        offset_rpm,
        f_min_hz,
        f_max_hz,
        averages,
        window_mm,
    )
    return analyse(done, offset_rpm != 0.0)


def measure(
    m: Machine,
    axis: str,
    measurement: int = MECHANICS,
    excitation: int = PRBS,
    torque_pct: float = 2.0,
    speed_rpm: float = 20.0,
    position_mm: float = 0.1,
    offset_rpm: float = 30.0,
    f_min_hz: float = 5.0,
    f_max_hz: float | None = None,
    averages: int = 10,
    window_mm: float = 50.0,
) -> Generator[Wait, np.ndarray, Measured]:
    """Measure `measurement` on `axis` with a PRBS or a chirp (`excitation`) of
    `torque_pct` % of the torque limit, `speed_rpm` or `position_mm`, `averages` Welch
    averages from `f_min_hz` to `f_max_hz` (half the drive rate; the position loop: half the
    NC's), the motor turning at `offset_rpm` meanwhile, then back to where it started. The
    run ends (and the axis stops) when the axis leaves ±`window_mm` around its start."""
    ax, model = drive_axis(m, axis, "a frequency response")
    k = m.k
    cycle_s = k.cycle_s
    steps = model.substeps
    position = measurement == CLOSED_POSITION
    fs = 1.0 / cycle_s if position else 1.0 / model.sampling_s
    f_hi = min(f_max_hz or fs / 2.0, fs / 2.0)
    if not 0.0 < f_min_hz < f_hi:
        raise ExperimentError(f"f_min_hz must lie below f_max_hz ({f_hi:g} Hz)")
    nseg, order = _segment(fs, f_min_hz, excitation)
    count = nseg + (averages - 1) * (nseg // 2)  # Welch: `averages` halves-overlapping segments
    lead = round(LEAD_IN_S * fs)
    total_s = (count + lead) / fs
    v_offset = offset_rpm * RPM_TO_RAD_S * model.unit_per_rad  # mm/s (°/s)
    if abs(v_offset) * (total_s + 0.5) >= window_mm:
        raise ExperimentError(
            f"at {offset_rpm:g} rpm {ax.name} moves {abs(v_offset) * total_s:.1f} mm in the "
            f"{total_s:.1f} s of the measurement: more than the window of ±{window_mm:g} mm; "
            "a wider window, a lower offset or fewer averages"
        )
    if measurement == MECHANICS or measurement not in MEASUREMENTS:
        point, amplitude = PL.INJECT_TORQUE, torque_pct / 100.0 * model.torque_limit
    elif position:
        point, amplitude = PL.INJECT_POSITION, position_mm
    else:
        point, amplitude = PL.INJECT_SPEED, speed_rpm * RPM_TO_RAD_S
    exc = amplitude * _excitation(excitation, order, nseg, count + lead, fs, f_min_hz, f_hi)
    if position:  # one value per NC cycle, held over its drive steps
        exc = np.repeat(exc, steps)
    p0 = float(k.st[ax.slot, L.S_P_ACT])
    feed = abs(v_offset) * MM_MIN_PER_MM_S
    if v_offset != 0.0:
        target = p0 + math.copysign(window_mm, v_offset)
        out = m.submit(Move(ax.name, target, rapid=False, feed_mm_min=feed))
        if not isinstance(out, Accepted):
            why = out.error.message if isinstance(out, Refused) else str(out)
            raise ExperimentError(f"the offset motion was refused: {why}")
    what = MEASUREMENTS[measurement]
    try:
        if v_offset != 0.0:  # up to the offset speed first
            yield Wait(round(0.5 / cycle_s), f"{ax.name} runs up to {offset_rpm:g} rpm", total_s)
        k.start_probe(ax.slot, exc, point)
        done = 0
        need = math.ceil(len(exc) / steps)
        while done < need:
            rec = yield Wait(
                min(CHUNK_CYCLES, need - done), f"{ax.name}: {what} is measured", total_s
            )
            done += rec.shape[0]
            off = float(np.max(np.abs(rec[:, ax.slot, L.R_P_ACT] - p0)))
            if off > window_mm:
                m.submit(Reset())
                raise ExperimentError(
                    f"{ax.name} left the position window (±{window_mm:g} mm, {off:.2f} mm off): "
                    "the measurement was stopped; a smaller amplitude or a wider window"
                )
        trace = k.probe_trace().copy()
    except GeneratorExit:
        m.submit(Reset())
        raise
    finally:
        if k.probe[PL.PR_SLOT] == ax.slot:
            k.stop_probe()
    if v_offset != 0.0:  # the offset motion ends with the measurement (a reset brakes it)
        m.submit(Reset())
        while ax.state not in (AxisState.STANDSTILL, AxisState.ERROR):
            yield Wait(10, f"{ax.name} comes to rest", total_s)
        # and the axis goes back to where it started, at the offset's feed
        back = m.submit(Move(ax.name, p0, rapid=False, feed_mm_min=feed))
        if isinstance(back, Accepted):
            # until it is in its exact-stop window (the set-point ends before the lag has)
            window = ax.cfg.eng("kenngr.exact_stop_window")
            settle = round(SETTLE_S / cycle_s)
            yield Wait(10, f"{ax.name} returns to {p0:g}", total_s)
            while ax.state is not AxisState.ERROR and settle > 0:
                lag = abs(float(k.st[ax.slot, L.S_P_CMD] - k.st[ax.slot, L.S_P_ACT]))
                if ax.state is AxisState.STANDSTILL and lag <= window:
                    break
                if ax.state is AxisState.STANDSTILL:
                    settle -= 10
                yield Wait(10, f"{ax.name} returns to {p0:g}", total_s)
    tr = trace[::steps] if position else trace
    x, y = _signals(measurement, tr[lead:])
    if position:
        x, y = x - np.mean(x), y - np.mean(y)
    h = frf.h1(x, y, fs, nperseg=nseg).band(f_min_hz, f_hi)
    w = tr[lead:, PL.D_W_MOTOR]
    per_s = np.count_nonzero(np.signbit(w[1:]) != np.signbit(w[:-1])) / (len(w) / fs)
    return Measured(ax.name, measurement, h, 0.0 if position else float(per_s), total_s)


def _signals(measurement: int, tr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if measurement == CLOSED_SPEED:
        return tr[:, PL.D_W_REF], tr[:, PL.D_W_MOTOR]
    if measurement == OPEN_SPEED:
        return tr[:, PL.D_W_REF] - tr[:, PL.D_W_MOTOR], tr[:, PL.D_W_MOTOR]
    if measurement == CLOSED_POSITION:
        return tr[:, PL.D_P_REF], tr[:, PL.D_P_ACT]
    return tr[:, PL.D_TORQUE], tr[:, PL.D_W_MOTOR]


def _log_thin(f: np.ndarray) -> np.ndarray:
    """Indices of about MAX_PLOT_POINTS frequencies spaced evenly in log f."""
    if len(f) <= MAX_PLOT_POINTS:
        return np.arange(len(f))
    at = np.geomspace(f[0], f[-1], MAX_PLOT_POINTS)
    return np.unique(np.searchsorted(f, at).clip(0, len(f) - 1))


def _margins(h: frf.Frf, figures: list[Figure]) -> list[str]:
    """The open loop's margins read on its Nyquist curve (nc_sim/plant/tuning.py): the least
    phase margin over every gain crossover (a resonance that lifts the loop above 0 dB again
    has its own), the gain margin above the first crossover (a phase that wanders about
    -180° below it, where |L| is large, is no margin); each left out where the coherence
    says the estimate does not hold. Returns the notes."""
    fig = loop_figures(h.f_hz, h.h)
    if fig is None:
        return [
            "no margins: the measured loop has no gain crossover in the band, or it is not "
            "stable by the Nyquist criterion (it encircles -1)"
        ]
    notes = []
    for at, pairs in (
        (
            fig.crossover_hz,
            (
                (
                    "phase_margin_deg",
                    fig.phase_margin_deg,
                    "°",
                    "least phase margin at a crossover",
                ),
                ("crossover_hz", fig.crossover_hz, "Hz", "first gain crossover (|L| = 1)"),
            ),
        ),
        (
            fig.phase_crossover_hz,
            (
                ("gain_margin_db", fig.gain_margin_db, "dB", "gain margin at -180° above it"),
                ("phase_crossover_hz", fig.phase_crossover_hz, "Hz", "phase crossover (-180°)"),
            ),
        ),
    ):
        if at is None:
            continue
        holds = frf.coherence_near(h, at)
        if holds < 0.8:  # a margin read where the estimate does not hold is no margin
            notes.append(
                f"{pairs[0][0].replace('_', ' ')} left out: at {at:.1f} Hz the coherence is "
                f"{holds:.2f} (backlash or friction make the axis nonlinear there: less "
                "amplitude, an offset speed)"
            )
            continue
        for name, value, unit, text in pairs:
            if value is not None:
                figures.append(Figure(name, float(value), unit, text))
    return notes


def analyse(done: Measured, offset: bool) -> Result:
    """The figures, notes and Bode series of a measurement (`offset`: it ran at an offset
    speed)."""
    name, measurement, h = done.axis, done.measurement, done.h
    figures: list[Figure] = []
    notes: list[str] = []
    if measurement == MECHANICS:
        peaks, dips = frf.resonances(h)
        for i, f in enumerate(peaks):
            figures.append(Figure(f"resonance_{i + 1}_hz", f, "Hz", "a resonance (a peak)"))
        for i, f in enumerate(dips):
            figures.append(Figure(f"anti_resonance_{i + 1}_hz", f, "Hz", "an anti-resonance"))
        if peaks:
            first_dip = min(dips) if dips else 0.0
            notes.append(
                f"first resonance at {min(peaks):.1f} Hz"
                + (f", anti-resonance at {first_dip:.1f} Hz" if first_dip else "")
                + ": the coupling between motor and load"
            )
        else:
            notes.append("no resonance stands out: the mechanics behave as one rigid mass")
    if measurement == OPEN_SPEED:
        notes += _margins(h, figures)
    if measurement in (CLOSED_SPEED, CLOSED_POSITION):
        bw = frf.bandwidth_hz(h)
        if bw is not None:
            figures.append(Figure("bandwidth_hz", float(bw), "Hz", "-3 dB bandwidth"))
        peak = float(np.max(h.magnitude_db))
        figures.append(Figure("peak_db", peak, "dB", "highest magnitude (resonance peaking)"))
    per_s = done.reversals_per_s
    if per_s >= 1.0:
        cure = "a higher offset speed" if offset else "an offset speed"
        notes.append(
            f"the motor reversed {per_s:.0f} times a second: friction changes sign at each "
            f"reversal and distorts the low frequencies; {cure} keeps it constant"
        )
    coh = h.coherence
    poor = coh < 0.8
    figures.append(Figure("coherence_min", float(np.min(coh)), "", "lowest coherence"))
    if np.mean(poor) > 0.02:
        lo, hi = float(h.f_hz[poor][0]), float(h.f_hz[poor][-1])
        notes.append(
            f"coherence below 0.8 over {np.mean(poor):.0%} of the band ({lo:.0f} to {hi:.0f} "
            "Hz): read the curve there with care; less amplitude when backlash or friction "
            "make the axis nonlinear, more averages, an offset speed"
        )
    keep = _log_thin(h.f_hz)
    fx = tuple(float(v) for v in h.f_hz[keep])
    unit = "(rad/s)/Nm" if measurement == MECHANICS else ""  # the loops: a ratio
    series = (
        Series("magnitude_db", fx, tuple(float(v) for v in h.magnitude_db[keep]), "Hz", "dB"),
        Series("phase_deg", fx, tuple(float(v) for v in h.phase_deg[keep]), "Hz", "°"),
        Series("coherence", fx, tuple(float(v) for v in coh[keep]), "Hz", ""),
    )
    notes.insert(0, f"{name}: {MEASUREMENTS[measurement]}, H1 in {unit or 'the ratio of both'}")
    inputs: dict[str, float | int | str] = {"axis": name, "measurement": measurement}
    figures.append(
        Figure("measured_s", done.measured_s, "s", "excitation on the axis (machine time)")
    )
    return Result("frequency-response", tuple(figures), (), series, tuple(notes), inputs=inputs)
