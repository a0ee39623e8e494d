"""The plant's parameters in the axis list (the plant itself: nc_sim/plant). The drive
cascade has the numbers and units of one drive family, SINAMICS S120 (p0341, p1460, p1656 …);
the mechanics, friction and measuring system are our own `sim.*` entries (a machine's
physics, no drive parameter).

Values are stored as the registry's quantities give them: times in µs (SINAMICS shows ms),
torques in Nm, inertias in kg·m², frequencies in Hz, all referred to the motor shaft.
`sim.plant` chooses the model: IDEAL keeps the first-order speed lag `sim.drive_t`,
DRIVE_CASCADE runs the drive and mechanics below at the drive's own rate.
"""

from __future__ import annotations

from nc_sim.params.registry import DType, Effect, ParamDef, Scope
from nc_sim.units import Quantity

PLANT_SYMBOLS = {"IDEAL": 0, "DRIVE_CASCADE": 1}
MEASURING_SYMBOLS = {"INDIRECT": 0, "DIRECT": 1}  # encoder on the motor | on the load
# p1657 … filter types: PT2 low pass, general second-order filter (a notch, band-stop)
FILTER_TYPES = {"PT2_LOW_PASS": 1, "GENERAL_2ND_ORDER": 2}
CURRENT_FILTERS = 3  # filter 1, 2 and 3 of the current setpoint (p1656 bits 0, 1, 2)
# parameter IDs of current-setpoint filter i (0, 1, 2): type, denominator natural frequency
# and damping, numerator natural frequency and damping, five consecutive numbers from p1657
FILTER_FIRST_ID = 1657

R64, U32, ENUM = DType.REAL64, DType.UNS32, DType.ENUM
AXIS = Scope.AXIS
TIME = Quantity.TIME
HZ = Quantity.FREQUENCY
NONE = Quantity.NONE


def _def(
    pid: str,
    name: str,
    dtype: DType,
    q: Quantity,
    default: float | str,
    lo: float | None,
    hi: float | None,
    title: str,
    source: str = "sinamics",
    symbols: dict[str, int] | None = None,
    effect: Effect = Effect.NOW,
) -> ParamDef:
    return ParamDef(
        pid,
        name,
        AXIS,
        dtype,
        q,
        default,
        lo,
        hi,
        effect,
        "TRS",
        title,
        source,
        symbols or {},
        "",
    )


def _filter_defs(i: int) -> list[ParamDef]:
    first = FILTER_FIRST_ID + 5 * i
    n = i + 1
    base = f"drive.current_filter_{n}"
    return [
        _def(
            f"p{first}",
            f"{base}.type",
            ENUM,
            NONE,
            "PT2_LOW_PASS" if i == 0 else "GENERAL_2ND_ORDER",
            None,
            None,
            f"Current setpoint filter {n}: type (PT2 low pass or general second-order filter)",
            symbols=FILTER_TYPES,
        ),
        _def(
            f"p{first + 1}",
            f"{base}.denominator_frequency",
            R64,
            HZ,
            2000.0,
            0.5,
            16000.0,
            f"Current setpoint filter {n}: denominator natural frequency",
        ),
        _def(
            f"p{first + 2}",
            f"{base}.denominator_damping",
            R64,
            NONE,
            0.7,
            0.001,
            10.0,
            f"Current setpoint filter {n}: denominator damping",
        ),
        _def(
            f"p{first + 3}",
            f"{base}.numerator_frequency",
            R64,
            HZ,
            2000.0,
            0.5,
            16000.0,
            f"Current setpoint filter {n}: numerator natural frequency (general filter)",
        ),
        _def(
            f"p{first + 4}",
            f"{base}.numerator_damping",
            R64,
            NONE,
            0.0,
            0.0,
            10.0,
            f"Current setpoint filter {n}: numerator damping (0: a notch of infinite depth)",
        ),
    ]


PLANT_DEFINITIONS: list[ParamDef] = [
    _def(
        "INB-SIM-0020",
        "sim.plant",
        ENUM,
        NONE,
        "IDEAL",
        None,
        None,
        "Plant model: IDEAL (first-order speed lag sim.drive_t) or DRIVE_CASCADE (drive and "
        "mechanics)",
        source="inbetrieb",
        symbols=PLANT_SYMBOLS,
    ),
    _def(
        "p0115",
        "drive.sampling_time",
        U32,
        TIME,
        125,
        31,
        1000,
        "Sampling time of the drive's current and speed controllers (the NC cycle divided "
        "by a whole number)",
    ),
    _def(
        "INB-SIM-0021",
        "drive.current_loop_t",
        U32,
        TIME,
        250,
        10,
        10000,
        "Equivalent time constant of the closed current loop",
        source="inbetrieb",
    ),
    _def(
        "p1460",
        "drive.speed_kp",
        R64,
        Quantity.SPEED_GAIN,
        0.5,
        0.0,
        1000000.0,
        "Speed controller P gain",
    ),
    _def(
        "p1462",
        "drive.speed_tn",
        U32,
        TIME,
        10000,
        0,
        100000000,
        "Speed controller integral time (0: P controller)",
    ),
    _def(
        "p1416",
        "drive.speed_setpoint_filter_t",
        U32,
        TIME,
        0,
        0,
        1000000,
        "Speed setpoint filter 1 time constant (PT1, 0: off)",
    ),
    _def(
        "p1520",
        "drive.torque_limit",
        R64,
        Quantity.TORQUE,
        20.0,
        0.0,
        100000.0,
        "Torque limit (motoring and generating, referred to the motor)",
    ),
    _def(
        "p1656",
        "drive.current_filter_active",
        U32,
        NONE,
        0,
        0,
        (1 << CURRENT_FILTERS) - 1,
        "Current setpoint filters active: bit 0 filter 1, bit 1 filter 2, bit 2 filter 3",
    ),
    *[d for i in range(CURRENT_FILTERS) for d in _filter_defs(i)],
    _def(
        "p0341",
        "drive.motor_inertia",
        R64,
        Quantity.INERTIA,
        0.001,
        1e-7,
        1000.0,
        "Motor moment of inertia",
    ),
    _def(
        "p0342",
        "drive.inertia_ratio",
        R64,
        NONE,
        2.0,
        1.0,
        10000.0,
        "Ratio between the total and the motor moment of inertia (load referred to the motor)",
    ),
    _def(
        "INB-SIM-0022",
        "sim.mech.anti_resonance",
        R64,
        HZ,
        0.0,
        0.0,
        5000.0,
        "Anti-resonance frequency of the coupling (the load on the spring, motor held; 0: rigid)",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0023",
        "sim.mech.damping",
        R64,
        NONE,
        0.05,
        0.0,
        1.0,
        "Damping of the coupling at the anti-resonance (Lehr's damping)",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0024",
        "sim.mech.travel_per_rev",
        R64,
        Quantity.POSITION,
        100000.0,
        1.0,
        1e12,
        "Load travel per motor revolution (ball screw lead over the gear ratio)",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0025",
        "sim.mech.coulomb_friction",
        R64,
        Quantity.TORQUE,
        0.0,
        0.0,
        10000.0,
        "Coulomb friction torque of the load, referred to the motor",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0026",
        "sim.mech.breakaway_torque",
        R64,
        Quantity.TORQUE,
        0.0,
        0.0,
        10000.0,
        "Breakaway (static) friction torque; the Stribeck curve falls from it to the Coulomb "
        "torque (below the Coulomb torque: none)",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0027",
        "sim.mech.stribeck_speed",
        R64,
        Quantity.RPM,
        10.0,
        0.001,
        100000.0,
        "Stribeck speed of the motor: how fast the friction falls from breakaway to Coulomb",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0028",
        "sim.mech.viscous_friction",
        R64,
        Quantity.SPEED_GAIN,
        0.0,
        0.0,
        10000.0,
        "Viscous friction of the load, referred to the motor",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0029",
        "sim.mech.backlash",
        R64,
        Quantity.POSITION,
        0.0,
        0.0,
        1e9,
        "Backlash between motor and load",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0030",
        "sim.measuring_system",
        ENUM,
        NONE,
        "DIRECT",
        None,
        None,
        "Where the NC's measuring system sits: INDIRECT on the motor, DIRECT on the load",
        source="inbetrieb",
        symbols=MEASURING_SYMBOLS,
    ),
    # a spindle's gear stage changes what the motor drives: the travel per motor revolution
    # and the load inertia referred to the motor (SINAMICS keeps p0342 per drive data set)
    _def(
        "INB-SIM-0031",
        "sim.getriebe[i].travel_per_rev",
        R64,
        Quantity.POSITION,
        0.0,
        0.0,
        1e12,
        "Load travel per motor revolution in this gear stage (0: sim.mech.travel_per_rev)",
        source="inbetrieb",
    ),
    _def(
        "INB-SIM-0032",
        "sim.getriebe[i].inertia_ratio",
        R64,
        NONE,
        0.0,
        0.0,
        10000.0,
        "p0342 in this gear stage: total over motor moment of inertia (0: p0342)",
        source="inbetrieb",
    ),
]
