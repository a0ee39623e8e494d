"""Column layout of the plant's kernel arrays: `pl` (the drive and mechanics of each slot as
pushed, with the discretised linear part) and `ps` (their state); compile-time constants.

The linear part's state vector x has the mechanics first, then the active filters' states:
the kernel reads the mechanics at fixed indices, and a slot with fewer filters has fewer
states (`PL_NX`), so it costs less.
"""

from __future__ import annotations

MODEL_IDEAL = 0
MODEL_CASCADE = 1

# --- x: the linear part's states (motor-referred SI units) --------------------------------
X_WM = 0  # motor speed (rad/s)
X_WL = 1  # load speed (rad/s); two-mass only
X_DEF = 2  # coupling deflection, motor minus load angle (rad); two-mass only
X_TRAVEL = 3  # angle the load (rigid: the motor) turned in this drive step (rad), then reset
X_TORQUE = 4  # motor torque: the current loop's output (Nm)
X_FILTERS = 5  # two states per active current-setpoint filter from here
NX_MAX = X_FILTERS + 2 * 3

# --- u: the linear part's inputs, held over a drive step ----------------------------------
U_TORQUE = 0  # torque setpoint after the limit, one drive step late (computing time)
U_FRICTION = 1  # friction torque on the load (rigid: on the one mass)
U_PLAY = 2  # backlash: the spring torque the gap takes away (+ motor, - load)
NU = 3

# --- pl: per-slot parameters -----------------------------------------------------------------
PL_MODEL = 0  # MODEL_*
PL_SUBSTEPS = 1  # drive steps per NC cycle
PL_KP = 2  # speed controller gain (Nm·s/rad)
PL_INV_TN = 3  # 1 / integral time (1/s), 0 for a P controller
PL_T_MAX = 4  # torque limit (Nm)
PL_SP_ALPHA = 5  # speed setpoint PT1: share of a step per drive step (1: no filter)
PL_UNIT_PER_RAD = 6  # load travel per motor radian (mm | °)
PL_TWO_MASS = 7  # 1: motor and load on a spring, 0: rigid
PL_DIRECT = 8  # 1: the NC's measuring system on the load, 0: on the motor
PL_COULOMB = 9  # Coulomb friction (Nm)
PL_BREAKAWAY = 10  # breakaway friction (Nm), >= Coulomb
PL_STRIBECK = 11  # Stribeck speed (rad/s)
PL_HALF_PLAY = 12  # half the backlash: rigid in load units (mm | °), two-mass in rad
PL_K = 13  # coupling stiffness (Nm/rad)
PL_D = 14  # coupling damping (Nm·s/rad)
PL_NX = 15  # states in use
# 1: the position loop closes in the drive, at its steps (antr.operation_mode); the NC
# sends its position command and the drive interpolates it; 0: in the NC, at its cycle
PL_POS_IN_DRIVE = 16
PL_AD = 17  # discretised state matrix, NX_MAX × NX_MAX, row-major
PL_BD = PL_AD + NX_MAX * NX_MAX  # discretised input matrix, NX_MAX × NU, row-major
PL_COLS = PL_BD + NX_MAX * NU

# --- ps: per-slot state ------------------------------------------------------------------
PS_X = 0  # x, NX_MAX columns
PS_INTEGRAL = NX_MAX  # integral of the speed error (rad)
PS_T_LATE = NX_MAX + 1  # torque setpoint waiting for the next drive step (Nm)
PS_W_REF = NX_MAX + 2  # speed setpoint after its filter (rad/s)
PS_NEXT = NX_MAX + 3  # scratch: x after the step being computed, NX_MAX columns
PS_COLS = PS_NEXT + NX_MAX

# --- the drive trace: one row per drive step of the probed slot ----------------------------
D_W_REF = 0  # speed setpoint the controller sees, excitation included (rad/s)
D_W_MOTOR = 1  # motor speed (rad/s)
D_W_LOAD = 2  # load speed (rad/s)
D_T_SET = 3  # torque setpoint after the limit, excitation included (Nm)
D_TORQUE = 4  # motor torque, the current loop's output (Nm)
D_X_MOTOR = 5  # motor position in load units (mm | °)
D_X_LOAD = 6  # load position (mm | °)
D_W_SET = 7  # speed setpoint from the NC, before the drive's setpoint filter (rad/s)
# the position loop: the command the controller sees (excitation included) and the actual
# position it compares it with (NC coordinates, mm | °); held over the NC cycle when the
# loop closes in the NC, the drive's own values per drive step when it closes in the drive
D_P_REF = 8
D_P_ACT = 9
D_COLS = 10

# probe: where the excitation goes in (added to the torque or the speed setpoint, or to the
# position command as the position controller sees it: held over the NC cycle in the NC,
# per drive step in the drive)
INJECT_TORQUE = 0
INJECT_SPEED = 1
INJECT_POSITION = 2
# at the speed setpoint with the NC's position loop open: the NC follows the actual position
# meanwhile (as in speed control), so a speed step is the speed loop's alone
INJECT_SPEED_OPEN = 3
# probe integer row
PR_SLOT = 0  # probed slot, -1: none
PR_LEN = 1  # samples of excitation and trace
PR_POS = 2  # samples done
PR_POINT = 3  # INJECT_*
PR_WRAP = 4  # 1: a ring (the scope's drive-rate capture): samples wrap to 0 at PR_LEN, endless
PR_COUNT = 5  # samples recorded since the probe started
PR_COLS = 6
