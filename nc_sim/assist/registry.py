"""Every commissioning assistant, described once (nc_sim/assist/descriptor.py). The API's
request models and routes, the command line's options, the HMI's forms, the stored runs'
summaries and the report's sections are all made from these descriptors; adding an assistant
is its procedure module, its entry in `ASSISTANTS` (a drive measurement's in
nc_sim/assist/drive_registry.py) and its tests.
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
from nc_sim.assist.drive_registry import DRIVE_ASSISTANTS

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
    *DRIVE_ASSISTANTS,
)
"""Every assistant, in the order the HMI offers them."""

BY_NAME: dict[str, Assistant] = {a.name: a for a in ASSISTANTS}


def assistant(name: str) -> Assistant:
    """The descriptor of `name` (KeyError naming the known ones)."""
    try:
        return BY_NAME[name]
    except KeyError:
        raise KeyError(f"no assistant {name!r} ({', '.join(BY_NAME)})") from None
