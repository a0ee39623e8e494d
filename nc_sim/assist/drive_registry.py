"""The drive's own measurements and what builds on them, described once: frequency response,
the speed-loop autotune, step response, drive trace and the circularity test (the rest of the
assistants: nc_sim/assist/registry.py, which lists these after its own).
"""

from __future__ import annotations

from nc_sim.assist.descriptor import Assistant, AxisChoice, AxisKind, Choice, Kind, Number

_AXES: tuple[AxisKind, ...] = ("linear", "rotary")
# the excitation of a frequency response, which the autotune measures with too
TORQUE_PCT = Number("torque_pct", "amplitude at the torque, % of p1520", "%", 0, 100, True, 2.0)
F_MIN = Number("f_min_hz", "lowest frequency, Hz", "Hz", 0.1, 1000, default=5.0, cli="f-min")
WINDOW = Number("window_mm", "position window, ± mm", "mm", 0, 1000, True, 50.0, cli="window")


def _speed(default: float) -> Number:
    return Number(
        "speed_rpm", "amplitude at the speed setpoint, rpm", "rpm", 0, 3000, True, default
    )


def _offset(default: float) -> Number:
    text = "offset speed of the motor, rpm (friction stays one-sided)"
    return Number("offset_rpm", text, "rpm", -3000, 3000, default=default)


def _averages(default: int) -> Number:
    return Number("averages", "Welch averages", "", 1, 50, default=default, integer=True)


DRIVE_ASSISTANTS: tuple[Assistant, ...] = (
    Assistant(
        "frequency-response",
        "Frequency response (Bode)",
        "drive: speed loop",
        "An excitation (PRBS or chirp) goes into the drive at its own rate while the NC holds "
        "the axis or moves it at `offset_rpm`; from the drive trace H1 = Pxy/Pxx with Welch "
        "averaging and the coherence: the mechanics (torque to motor speed) with its "
        "resonances, the closed or open speed loop with margins and bandwidth, or the closed "
        "position loop. The axis must run the drive cascade (sim.plant).",
        Kind.EXPERIMENT,
        "FrequencyResponseRequest",
        (
            AxisChoice(kinds=_AXES),
            Choice(
                "measurement",
                "what is measured",
                (
                    (1, "mechanics"),
                    (2, "closed speed loop"),
                    (3, "open speed loop"),
                    (4, "closed position loop"),
                ),
                1,
            ),
            Choice("excitation", "excitation", ((1, "PRBS"), (2, "chirp")), 1),
            TORQUE_PCT,
            _speed(20.0),
            Number("position_mm", "amplitude at the position command, mm", "mm", 0, 10, True, 0.1),
            _offset(30.0),
            F_MIN,
            Number(
                "f_max_hz",
                "highest frequency, Hz (null: half the sampling rate)",
                "Hz",
                0,
                100000,
                True,
                None,
                optional=True,
                cli="f-max",
            ),
            _averages(10),
            WINDOW,
        ),
        "nc_sim.assist.frequency_response:frequency_response_experiment",
        ("resonance_1_hz", "phase_margin_deg", "gain_margin_db", "bandwidth_hz"),
        live="nc_sim.assist.frequency_response:frequency_response",
    ),
    Assistant(
        "step-response",
        "Step response",
        "drive: speed and position loop",
        "A small step from rest: of the speed setpoint at the drive (the NC's position loop "
        "open meanwhile; the axis goes back afterwards) or of the position command. Rise "
        "time, overshoot and settling time beside what the drive's own parameters expect on "
        "a rigid axis. The axis must run the drive cascade (sim.plant).",
        Kind.EXPERIMENT,
        "StepResponseRequest",
        (
            AxisChoice(kinds=_AXES),
            Choice("loop", "which loop", ((1, "speed loop"), (2, "position loop")), 1),
            Number("speed_rpm", "speed step, rpm", "rpm", 0, 3000, True, 50.0),
            Number("position_mm", "position step, mm", "mm", 0, 10, True, 0.05),
            Number("duration_s", "recorded for, s", "s", 0.02, 10, default=0.5),
        ),
        "nc_sim.assist.step_response:step_response_experiment",
        ("rise_ms", "overshoot_pct", "settling_ms"),
        live="nc_sim.assist.step_response:step_response",
    ),
    Assistant(
        "drive-trace",
        "Drive trace",
        "drive: its oscilloscope",
        "The drive's own signals at its sampling rate (8 kHz at 125 µs) from the start of a "
        "short move: speed setpoint and actual, the load's speed, torque setpoint and torque, "
        "and how far the motor is ahead of the load (the coupling's twist, backlash taken "
        "up); the axis goes back afterwards. The axis must run the drive cascade (sim.plant).",
        Kind.EXPERIMENT,
        "DriveTraceRequest",
        (
            AxisChoice(kinds=_AXES),
            Number("distance", "move, mm (° for rotary); 0: at rest", "mm", -100, 100, default=5.0),
            Number("feed_mm_min", "feed, mm/min", "mm/min", 0, 1e5, True, 3000.0, cli="feed"),
            Number("duration_s", "recorded for, s", "s", 0.001, 2, default=0.5),
        ),
        "nc_sim.assist.drive_trace:drive_trace_experiment",
        ("torque_peak_nm", "twist_peak_um"),
        live="nc_sim.assist.drive_trace:drive_trace",
    ),
    Assistant(
        "autotune",
        "Speed-loop autotune",
        "drive: speed loop",
        "Measures the mechanics (for the resonance) and the open speed loop as the drive runs "
        "it, divides the drive's own PI out and searches gain, integral time and a notch on "
        "the measured resonance for the highest bandwidth that keeps the template's phase "
        "and gain margin (stiff 45°/8 dB, medium 55°/12 dB, soft 60°/20 dB); says what "
        "stopped the gain. On a copy the new values are measured again (achieved margins "
        "beside the target); it proposes kv for the tuned speed loop and shows the lag the "
        "feedforward leaves. "
        "The axis must run the drive cascade (sim.plant).",
        Kind.EXPERIMENT,
        "AutotuneRequest",
        (
            AxisChoice(kinds=_AXES),
            Choice(
                "template",
                "stability template",
                ((1, "stiff: 45°, 8 dB"), (2, "medium: 55°, 12 dB"), (3, "soft: 60°, 20 dB")),
                1,
            ),
            TORQUE_PCT,
            _speed(10.0),
            _offset(60.0),
            F_MIN,
            _averages(6),
            WINDOW,
        ),
        "nc_sim.assist.autotune:autotune_experiment",
        ("bandwidth_hz", "pm_achieved_deg", "gm_achieved_db", "kp"),
        live="nc_sim.assist.autotune:autotune_live",
    ),
    Assistant(
        "circle",
        "Circularity test",
        "ISO 230-4",
        "The NC runs a G02/G03 circle about where the plane's axes stand, with overrun arcs "
        "so the measured turn is at constant feed, counter-clockwise and clockwise, and "
        "records commanded and actual positions: circular, radial and bidirectional "
        "deviation about the least-squares centre, the radius change, the ellipse (servo "
        "mismatch turns over with the direction, squareness and scale do not), reversal "
        "spikes, lost motion and the effective kv of both axes, with kv matching proposed. "
        "Measured on the NC's feedback (annex E) or on the true path (a ballbar's view, the "
        "simulated machine's).",
        Kind.EXPERIMENT,
        "CircleRequest",
        (
            Choice("plane", "plane", ((17, "G17 XY"), (18, "G18 ZX"), (19, "G19 YZ")), 18),
            Number("radius_mm", "radius, mm", "mm", 0, 500, True, 10.0, cli="radius"),
            Number("feed_mm_min", "feed, mm/min", "mm/min", 0, 1e5, True, 1000.0, cli="feed"),
            Choice(
                "direction",
                "direction",
                ((0, "both: CCW, then CW"), (3, "CCW (G03)"), (2, "CW (G02)")),
                0,
            ),
            Number(
                "start_deg",
                "start angle, ° from the plane's first axis",
                "°",
                -360,
                360,
                default=0.0,
                cli="start",
            ),
            Number(
                "overrun_deg",
                "overrun arc before and after, °",
                "°",
                0,
                180,
                default=90.0,
                cli="overrun",
            ),
            Choice(
                "path",
                "measured on",
                ((1, "the NC's feedback (annex E)"), (2, "the true path (a ballbar)")),
                1,
            ),
        ),
        "nc_sim.assist.circle_test:circle_test_experiment",
        ("circular_um", "bidirectional_um", "ellipse_ccw_um", "kv_mismatch_ms"),
        live="nc_sim.assist.circle_test:circle_test",
    ),
)
