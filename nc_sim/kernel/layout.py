"""Column layout of the kernel's arrays: one row (slot) per axis or spindle of every machine.

`st` float state, `pr` float parameters (engineering units), `ist` integer state,
`seg` the active setpoint plan per slot, `rec` one sample row per cycle and slot.
Module-level integers are compile-time constants for numba.
"""

from __future__ import annotations

# --- st: float state ---------------------------------------------------------------------
S_P_CMD = 0  # commanded position (mm | °)
S_V_CMD = 1  # commanded velocity (unit/s)
S_A_CMD = 2  # commanded acceleration (unit/s²)
S_P_ACT = 3  # actual position as the NC sees it (after encoder, sign, offset)
S_V_ACT = 4  # actual velocity from the encoder difference
S_LAG = 5  # p_cmd - p_act
S_X_MOTOR = 6  # physical position of the load (true, before encoder)
S_V_MOTOR = 7  # physical velocity
S_U = 8  # velocity command of the position controller (unit/s)
S_DA = 9  # manipulated variable at the D/A (digits)
S_SEG_TAU = 10  # time into the current segment (s)
S_SEG_P0 = 11  # position at the start of the current segment
S_SEG_V0 = 12  # velocity at the start of the current segment
S_TARGET = 13  # target of a position plan, NaN for a velocity plan
S_LAG_MODEL = 14  # lag an ideal loop would have (dynamic lag monitoring)
S_V_GOAL = 15  # speed the spindle is commanded to reach (for speed reached), unit/s
S_V_TARGET = 16  # end speed of a curve-controlled speed change (I_CURVE), unit/s
S_OVERRIDE = 17  # override in force as a fraction (written by the Python layer, recorded)
S_V_MODEL = 18  # drive speed of the ideal loop the lag monitoring compares with
S_PLAY = 19  # backlash: how far the motor is ahead of the load (S_X_MOTOR), within ±width/2
# G201 [002 §2.6.2]: a path axis' manual motion on top of the path, planned on the slot's own
# plan (I_PLAN_*, S_SEG_*) while the path drives the slot; P, V, A in this order like S_P_CMD…
S_MAN_P = 20  # manual offset added to the path's command position
S_MAN_V = 21  # its velocity
S_MAN_A = 22  # its acceleration
S_MAN_TARGET = 23  # its target, NaN for a velocity plan (a jog braking to a hold)
S_P_TRUE = 24  # the load's true position at the encoder's sample, in NC coordinates (R_P_TRUE)
S_COLS = 25

# --- pr: float parameters (engineering units) -----------------------------------------------
P_KV = 0  # 1/s
P_FF = 1  # velocity feedforward weight 0..1
P_MG = 2  # NC multi_gain: digits for 1 m/min or 1000 °/min
P_DRV_GAIN = 3  # the drive's true digits for 1 m/min or 1000 °/min
P_DA_MAX = 4  # D/A limit, digits
P_SIGN_CMD = 5  # -1 when vz_stellgr
P_SIGN_FB = 6  # -1 when vz_istw
P_MOTOR_SIGN = 7  # -1 when the motor is wired inverted
P_ENC_SIGN = 8  # -1 when the encoder counts inverted
P_DRV_ALPHA = 9  # drive velocity loop: 1 - exp(-cycle/T), the share of a step per cycle
P_DRV_A_MAX = 10  # drive acceleration limit (unit/s²), 0 = none
P_ENC_INC = 11  # encoder increment (mm | °), 0 = ideal
P_LAG_MAX = 12  # allowed deviation from the modelled lag
P_SWE_NEG = 13  # software limits (NC position), checked when P_LIMITS_ON
P_SWE_POS = 14
P_CAM_POS = 15  # physical position of the reference cam edge
P_ENC_OFFSET = 16  # NC position = sign·encoder + offset (set by homing)
P_SPEED_BAND = 17  # speed reached band as a fraction (vb_prozent · 0.001)
P_V_ZERO = 18  # spindle stopped below this speed (unit/s)
P_V_CTRL_LIMIT = 19  # vb_regelgrenze: above it the position loop opens, reference lost
P_V_SPEED_CTRL = 20  # P-AXIS-00767: changeover to speed control when I_SPEED_CTRL_ARMED
P_MODULO = 21  # 360 for spindles (zero mark once per revolution), 0 for linear axes
P_INPOS_WIN = 22  # exact-stop window around the target of a position plan
P_SENSORLESS = 23  # 1: no encoder, actual values from the command
P_CURVE_TYPE = 24  # beschl_kennlinie.typ: 0 none, 1 hyperbola, 2 polynomial, 3 asynchronous
P_N_LIMIT = 25  # n_grenz (°/s)
P_A_KONST = 26
P_B1 = 27
P_B2 = 28
P_B3 = 29
P_A_MIN = 30  # floor of every curve
P_CURVE_A_MAX = 31  # type 3: acceleration below N1
P_N1 = 32
P_N2 = 33
P_A_CAP = 34  # hard cap on curve acceleration (a_max, tool a_max)
P_V_RESO = 35  # speed-controlled spindle: drive digits per unit/s (v_reso), 0 = position loop
# the plant's faults (nc_sim/axis/plant.py): 1, 0, 0, 0 for a sound plant
P_ENC_FACTOR = 36  # the encoder counts this factor times the load's true position
P_ENC_NOISE = 37  # white noise on the encoder's reading, rms (mm | °)
P_FRICTION = 38  # Coulomb friction: speed the drive loses against the motion (unit/s)
P_BACKLASH = 39  # play between motor and load (mm | °)
P_COLS = 40

# --- ist: integer state -----------------------------------------------------------------
I_PLAN_N = 0  # segments in the active plan (0 = none: hold velocity)
I_PLAN_K = 1  # current segment
I_STATE = 2  # AxisState, written by the Python layer
I_EVENTS = 3  # EV_* bits raised in this batch, cleared by the Python layer
I_ENABLED = 4  # 1 when the drive enables are all present
I_JOB_ERROR = 5  # active job error code (0 none)
I_OPEN_LOOP = 6  # 1: speed control, position loop open
I_CAM = 7  # reference cam signal
I_HOMED = 8
I_LIMITS_ON = 9  # software limits monitored (linear axes once homed)
I_GEAR = 10  # active gear stage 1..6
I_SPEED_REACHED = 11
I_STOPPED = 12
I_SPEED_CTRL_ARMED = 13  # M3/M4 programmed above P-AXIS-00767: open the loop when passing it
I_CURVE = 14  # 1: curve-controlled speed change towards S_V_TARGET in progress
I_IN_POS = 15  # position plan ended and the actual position is inside the window
I_MON_ACTIVE = 16  # speed monitoring active (endless rotation with a commanded speed)
I_MON_INVALID = 17  # speed monitoring invalid (speed still changing, or no valid measurement)
I_MARK_ARMED = 18  # spindle: report the zero mark (homing waits for it)
I_ROLE = 19  # ROLE_*: what drives this slot's setpoint
I_LINE = 20  # program line of the block the slot's motion belongs to (0 none)
I_ROTARY_MODE = 21  # 1: a main spindle is the rotary axis C (written by the Python layer)
I_NOISE_STATE = 22  # xorshift32 state of the encoder noise (seeded when the noise starts)
I_COLS = 23

# I_ROLE values
ROLE_AXIS = 0  # its own plan (jog, single-axis move, spindle)
ROLE_PATH_AXIS = 1  # its channel's path writes its setpoint (coupled path mode)
ROLE_CHANNEL = 2  # a channel: S_P_CMD path length, S_V_CMD path speed; no drive behind it

# I_OPEN_LOOP values
LOOP_CLOSED = 0
LOOP_CONTROL_LIMIT = 1  # above vb_regelgrenze: actual values simulated, reference lost
LOOP_SPEED_CONTROL = 2  # changeover P-AXIS-00767, a speed-controlled or sensorless spindle

# --- events (bits in ist[:, I_EVENTS]) ---------------------------------------------------
EV_PLAN_DONE = 1
EV_LAG = 2
EV_SWLIMIT = 4
EV_CAM = 8
EV_SPEED_REACHED = 16
EV_LOOP = 32  # the kernel opened or closed the position loop
EV_IN_POS = 64  # exact stop reached
EV_BLOCK = 128  # channel: the path entered the next element (block)

# --- rec: one row per cycle and slot --------------------------------------------------------
R_P_CMD = 0
R_P_ACT = 1
R_LAG = 2
R_V_CMD = 3
R_V_ACT = 4
R_A_CMD = 5
R_STATE = 6
R_JOB_ERROR = 7
R_SPEED_REACHED = 8
R_STOPPED = 9
R_GEAR = 10
R_DA = 11
R_OPEN_LOOP = 12
R_HOMED = 13
R_IN_POS = 14
R_MON_ACTIVE = 15
R_MON_INVALID = 16
R_OVERRIDE = 17
R_LINE = 18
R_ROTARY_MODE = 19
R_MVPOS = 20  # actual speed above the noise of an axis at rest (P_INPOS_WIN per second)
R_MVNEG = 21
R_READY = 22  # the drive follows (I_ENABLED)
# the load's true position in NC coordinates (sign and homing offset, no encoder error):
# what a laser or a ballbar measures, which only the simulated machine knows
R_P_TRUE = 23
R_COLS = 24

# --- the path of a channel (coupled path mode) ------------------------------------------------
MAX_PATH_AXES = 6
PATH_ELEMENTS = 64  # geometry ring: the element being run and the look-ahead behind it
PATH_SEGMENTS = 512  # 1-D plan over the path length across the look-ahead window

# pi: integer row per path
PI_SLOT = 0  # the channel's own slot (ROLE_CHANNEL)
PI_NAX = 1  # axes in the path
PI_HEAD = 2  # ring index of the element being run
PI_COUNT = 3  # elements in the ring (0: no path motion)
PI_AX0 = 4  # slots of the path axes, MAX_PATH_AXES of them
PI_COLS = PI_AX0 + MAX_PATH_AXES

# pel: one geometry element (a block's line or arc) of the ring
E_ARC = 0  # 0 line, 1 arc in the plane (E_I0, E_I1)
E_S0 = 1  # path length at its start
E_LEN = 2  # its length
E_LINE = 3  # program line
E_I0 = 4  # arc: index (in the path's axes) of the plane's first axis
E_I1 = 5  # ... and second axis
E_CX = 6  # arc centre in the plane
E_CY = 7
E_R = 8  # arc radius
E_PHI0 = 9  # angle of the start point about the centre (rad)
E_DPHI = 10  # swept angle, signed (+ counter-clockwise in the plane's orientation)
E_P0 = 11  # start position per path axis (MAX_PATH_AXES columns)
E_LIN = E_P0 + MAX_PATH_AXES  # per path axis: position change per unit path length (not arc)
# spindle-coupled elements (G33 thread cutting, G63 tapping): the path length follows the
# spindle's actual angle instead of the plan
E_SPDL = E_LIN + MAX_PATH_AXES  # the spindle's slot + 1 (0: not coupled)
E_KIND = E_SPDL + 1  # COUPLE_THREAD or COUPLE_TAP
E_K = E_SPDL + 2  # path length per degree of spindle rotation (> 0)
E_DIR = E_SPDL + 3  # +1 / -1: the spindle's direction of rotation
E_TH0 = E_SPDL + 4  # spindle angle at which the coupling starts (phi = 0)
E_PHI_IN = E_SPDL + 5  # thread: angle over which the path accelerates (degrees of rotation)
E_PHI_OUT = E_SPDL + 6  # thread: angle over which it brakes
E_PHI_TOT = E_SPDL + 7  # thread: angle at which the element ends
E_COLS = E_SPDL + 8

COUPLE_THREAD = 1  # G33: the path follows the rotating spindle from its zero passage on
COUPLE_TAP = 2  # G63: the path follows the spindle's own position move to its end
