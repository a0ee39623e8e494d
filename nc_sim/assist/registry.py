"""Every commissioning assistant, described once (nc_sim/assist/descriptor.py). The API's
request models and routes, the command line's options, the HMI's forms, the stored runs'
summaries and the report's sections are all made from these descriptors; adding an assistant
is its procedure module, its entry in `ASSISTANTS` and its tests.
"""

from __future__ import annotations

from nc_sim.assist.descriptor import (
    Assistant,
    AxisChoice,
    AxisKind,
    Choice,
    Flag,
    Kind,
    Number,
    NumberList,
    Table,
)

GEAR = Number("gear", "gear stage 1-6 (M40-M45, getriebe[0-5])", "", 1, 6, default=1, integer=True)
GEAR_RATIO = Number(
    "gear_ratio", "i: motor revolutions per output revolution", "", 0, 1e6, True, 1.0
)
DIRECTION = Choice("direction", "the way it moves", ((1, "+ positive"), (-1, "− negative")), 1)
CURVE_TYPE = Choice(
    "typ", "curve type", ((1, "hyperbola"), (2, "polynomial"), (3, "asynchronous")), 2, cli="type"
)
N_LIMIT = Number(
    "n_limit_deg_s",
    "limit speed, °/s (null: searched)",
    "°/s",
    0,
    1e7,
    True,
    None,
    optional=True,
    cli="n-limit",
)
SPINDLE = AxisChoice(text="the spindle", kinds=("spindle",), cli="spindle")
_AXES: tuple[AxisKind, ...] = ("linear", "rotary")
_EXP = "nc_sim.assist.experiments"

ASSISTANTS: tuple[Assistant, ...] = (
    Assistant(
        "multi-gain",
        "multi_gain by experiment",
        "004 §3.6.2",
        "An axis at constant feed (a spindle turning position-controlled at constant speed): "
        "the lag averaged at constant speed, k = v/s, f = (kv/100)/k and the proposed "
        "multi_gain · f and kv / f.",
        Kind.EXPERIMENT,
        "MultiGainRequest",
        (
            AxisChoice(),
            Number(
                "feed_mm_min",
                "axis feed, mm/min (°/min for a rotary axis)",
                "mm/min",
                0,
                1e6,
                True,
                None,
                optional=True,
                cli="feed",
            ),
            Number(
                "speed_rpm",
                "spindle speed, rpm",
                "rpm",
                0,
                1e5,
                True,
                None,
                optional=True,
                cli="speed",
            ),
            Number("window_s", "averaged over, s", "s", 0.2, 30, default=1.0, cli="window"),
            DIRECTION,
        ),
        f"{_EXP}:multi_gain_experiment",
        ("k", "f", "kv_new"),
        live=f"{_EXP}:multi_gain",
    ),
    Assistant(
        "sign-check",
        "Direction and sign check",
        "004 §3.5",
        "A short slow move: a wrong sign of the manipulated variable (vz_stellgr) or of the "
        "actual value (vz_istw) is found before lag monitoring trips, from the way the machine "
        "moved (`observed`: +1 as commanded, -1 the other way; null: the simulated plant's).",
        Kind.EXPERIMENT,
        "SignCheckRequest",
        (
            AxisChoice(kinds=_AXES),
            Number("distance", "mm (° for rotary)", "mm", -100, 100, default=1.0),
            Number("feed_mm_min", "mm/min (°/min)", "mm/min", 0, 1e5, True, 100.0, cli="feed"),
            Choice(
                "observed",
                "the way the machine moved as you saw it",
                ((1, "+ as commanded"), (-1, "− the other way")),
                None,
                optional=True,
            ),
        ),
        f"{_EXP}:sign_check_experiment",
        ("max_lag", "lag_max", "runaway"),
        live=f"{_EXP}:sign_check",
    ),
    Assistant(
        "loop-gain",
        "Position loop gain (kv sweep)",
        "004 §3.6",
        "At each kv a G00 step and a G01 ramp on a copy; the highest kv whose step overshoots "
        "at most `overshoot_pct` and settles into the exact-stop window within `settle_ms` is "
        "proposed.",
        Kind.EXPERIMENT,
        "LoopGainRequest",
        (
            AxisChoice(kinds=_AXES),
            NumberList(
                "kvs",
                "kv values to try, 1/s (null: 0.5×-3×)",
                Number("kvs", "kv, 1/s", "1/s", 0, 10000, True),
                1,
                12,
                True,
                None,
                cli="kv",
            ),
            Number("overshoot_pct", "target: step overshoot, %", "%", 0, 100, default=5.0),
            Number("settle_ms", "target: step settling, ms", "ms", 0, 10000, True, 200.0),
            Number(
                "step",
                "G00 step, mm (° for rotary); null: 20 exact-stop windows",
                "mm",
                0,
                100,
                True,
                None,
                optional=True,
            ),
            Number(
                "feed_mm_min",
                "G01 ramp feed, mm/min (°/min); null: 5 % of rapid",
                "mm/min",
                0,
                1e5,
                True,
                None,
                optional=True,
                cli="feed",
            ),
            DIRECTION,
        ),
        "nc_sim.assist.loop_gain:loop_gain",
        ("kv", "kv_new"),
    ),
    Assistant(
        "curve-run-up",
        "Acceleration curve from a run-up",
        "000 §2.8.4",
        "The spindle runs up with M3 in the gear to its top speed (the gear's vb_max, or "
        "`speed_rpm`); a(n) from the recorded actual speed, the curve of type `typ` fitted by "
        "least squares and proposed as the gear's beschl_kennlinie.",
        Kind.EXPERIMENT,
        "CurveRunUpRequest",
        (
            SPINDLE,
            GEAR,
            CURVE_TYPE,
            Number(
                "speed_rpm",
                "top speed (default vb_max)",
                "rpm",
                0,
                1e5,
                True,
                None,
                optional=True,
                cli="rpm",
            ),
            N_LIMIT,
        ),
        "nc_sim.assist.run_up:curve_run_up",
        ("max_error", "run_up_s"),
    ),
    Assistant(
        "resolution",
        "Resolution",
        "004 §3.4",
        "wegaufz/wegaufn = encoder increments per motor revolution over the distance one "
        "motor revolution moves the axis (pitch / i in 0.1 µm, or 360° / i in 0.0001°): a "
        "linear axis gives `pitch_mm`, a rotary axis or spindle sets `rotary`.",
        Kind.CALCULATOR,
        "ResolutionRequest",
        (
            AxisChoice(),
            GEAR,
            Number(
                "increments_per_rev",
                "encoder increments per motor revolution",
                "",
                0,
                4294967295,
                True,
                integer=True,
                cli="increments",
            ),
            Number(
                "pitch_mm",
                "mm per output revolution",
                "mm",
                0,
                1e4,
                True,
                None,
                optional=True,
                cli="pitch",
            ),
            Flag("rotary", "rotary axis or spindle: 360° per revolution"),
            GEAR_RATIO,
        ),
        "nc_sim.assist.calculators:resolution_of",
    ),
    Assistant(
        "multi-gain-calc",
        "multi_gain by calculation",
        "004 §3.6.1",
        "multi_gain = f · n, the command value per motor rpm f (from exactly one drive "
        "scaling: digits per rpm, the D/A full scale, or a SERCOS weighting) times the motor "
        "speed n for 1 m/min (1000 °/min rotary, no `pitch_mm`) with the gear i.",
        Kind.CALCULATOR,
        "MultiGainCalcRequest",
        (
            AxisChoice(),
            GEAR,
            Number(
                "digits_per_rpm",
                "digits per motor rpm",
                "digits/rpm",
                0,
                1e9,
                True,
                None,
                optional=True,
            ),
            Number(
                "full_scale_digits",
                "command value at full scale, digits",
                "digits",
                0,
                2147483647,
                True,
                None,
                integer=True,
                optional=True,
            ),
            Number(
                "full_scale_rpm",
                "motor rpm at full scale",
                "rpm",
                0,
                1e6,
                True,
                None,
                optional=True,
            ),
            Number(
                "speed_weighting_rpm",
                "SERCOS rotary weighting, rpm per digit",
                "rpm/digit",
                0,
                1e3,
                True,
                None,
                optional=True,
                cli="weighting-rpm",
            ),
            Number(
                "speed_weighting_m_per_min",
                "SERCOS translatory weighting, m/min per digit",
                "m/min/digit",
                0,
                1e3,
                True,
                None,
                optional=True,
                cli="weighting-m-per-min",
            ),
            Number(
                "pitch_mm",
                "mm per output revolution",
                "mm",
                0,
                1e4,
                True,
                None,
                optional=True,
                cli="pitch",
            ),
            GEAR_RATIO,
        ),
        "nc_sim.assist.calculators:multi_gain_of",
    ),
    Assistant(
        "speed-scaling",
        "Speed scaling",
        "000 §2.2.4",
        "v_reso_num/v_reso_denom of a speed-controlled spindle: `increments` output turn the "
        "motor at `speed_rpm`, over the distance (0.001°) covered in the time base "
        "(P-AXIS-00207: 0 minute, 1 second, 2 cycle).",
        Kind.CALCULATOR,
        "SpeedScalingRequest",
        (
            SPINDLE,
            Number(
                "increments", "value output to the drive", "", 0, 4294967295, True, integer=True
            ),
            Number("speed_rpm", "motor speed at that value, rpm", "rpm", 0, 1e6, True, cli="rpm"),
            Choice("time_base", "time base", ((0, "minute"), (1, "second"), (2, "cycle")), 0),
            Number(
                "cycle_ms",
                "cycle time (time base 2; null: the machine's), ms",
                "ms",
                0,
                1000,
                True,
                None,
                optional=True,
            ),
            GEAR_RATIO,
        ),
        "nc_sim.assist.calculators:speed_scaling_of",
    ),
    Assistant(
        "curve-fit",
        "Acceleration curve fit",
        "000 §2.8.4",
        "The coefficients of the spindle gear's acceleration curve of type `typ` (1 hyperbola, "
        "2 polynomial, 3 asynchronous) through points: 4 (polynomial) or 3 (hyperbola) are "
        "interpolated with the first as (n_limit, a_konst), more fitted by least squares.",
        Kind.CALCULATOR,
        "CurveFitRequest",
        (
            SPINDLE,
            GEAR,
            CURVE_TYPE,
            Table(
                "points",
                "points n:a (°/s, °/s²)",
                "CurvePoint",
                (
                    Number("n_deg_s", "speed n, °/s", "°/s", 0, 1e7),
                    Number("a_deg_s2", "acceleration a, °/s²", "°/s²", 0, 1e9, True),
                ),
                3,
                500,
            ),
            N_LIMIT,
            Number("a_min", "the curve's floor, °/s²", "°/s²", 0, 1e9, default=0.0),
        ),
        "nc_sim.assist.curve_fit:curve_fit_of",
    ),
    Assistant(
        "resolution-check",
        "Resolution check",
        "004 §3.4",
        "The axis moves a known distance; the travel the NC counts is compared with the "
        "travel measured on the machine (`measured`, a dial gauge or laser; null: the "
        "simulated plant's). k = NC travel / measured travel; beyond what the measurement "
        "resolves, wegaufz/wegaufn · k is proposed.",
        Kind.EXPERIMENT,
        "ResolutionCheckRequest",
        (
            AxisChoice(kinds=_AXES),
            Number("distance", "distance to move (° for rotary)", "mm", -1000, 1000, default=10.0),
            Number(
                "feed_mm_min",
                "feed (°/min for rotary)",
                "mm/min",
                0,
                1e5,
                True,
                1000.0,
                cli="feed",
            ),
            Number(
                "measured",
                "travel measured on the machine (empty: the simulated plant's)",
                "mm",
                -1000,
                1000,
                default=None,
                optional=True,
            ),
        ),
        "",  # on a copy: the live procedure as it is
        ("k", "deviation_ppm"),
        live="nc_sim.assist.resolution_check:resolution_check",
    ),
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
            Number("torque_pct", "amplitude at the torque, % of p1520", "%", 0, 100, True, 2.0),
            Number("speed_rpm", "amplitude at the speed setpoint, rpm", "rpm", 0, 3000, True, 20.0),
            Number("position_mm", "amplitude at the position command, mm", "mm", 0, 10, True, 0.1),
            Number(
                "offset_rpm",
                "offset speed of the motor, rpm (friction stays one-sided)",
                "rpm",
                -3000,
                3000,
                default=30.0,
            ),
            Number("f_min_hz", "lowest frequency, Hz", "Hz", 0.1, 1000, default=5.0, cli="f-min"),
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
            Number("averages", "Welch averages", "", 1, 50, default=10, integer=True),
            Number("window_mm", "position window, ± mm", "mm", 0, 1000, True, 50.0, cli="window"),
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
        "beside the target); kv for the tuned speed loop and the lag feedforward leaves. "
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
            Number("torque_pct", "amplitude at the torque, % of p1520", "%", 0, 100, True, 2.0),
            Number("speed_rpm", "amplitude at the speed setpoint, rpm", "rpm", 0, 3000, True, 10.0),
            Number(
                "offset_rpm",
                "offset speed of the motor, rpm (friction stays one-sided)",
                "rpm",
                -3000,
                3000,
                default=60.0,
            ),
            Number("f_min_hz", "lowest frequency, Hz", "Hz", 0.1, 1000, default=5.0, cli="f-min"),
            Number("averages", "Welch averages", "", 1, 50, default=6, integer=True),
            Number("window_mm", "position window, ± mm", "mm", 0, 1000, True, 50.0, cli="window"),
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
"""Every assistant, in the order the HMI offers them."""

BY_NAME: dict[str, Assistant] = {a.name: a for a in ASSISTANTS}


def assistant(name: str) -> Assistant:
    """The descriptor of `name` (KeyError naming the known ones)."""
    try:
        return BY_NAME[name]
    except KeyError:
        raise KeyError(f"no assistant {name!r} ({', '.join(BY_NAME)})") from None
