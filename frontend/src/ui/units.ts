// The HMI's unit conversions, in one place (the service's are in nc_sim/units.py).
export const MM_MIN_PER_MM_S = 60;
export const RPM_TO_DEG_S = 6; // 1 rpm = 360°/60 s
const MM_PER_UM = 1e-3; // a list's raw velocity counts µm/s (0.001°/s)

/** A feed or speed per minute (mm/min, °/min) as per second. */
export const perSecond = (perMin: number): number => perMin / MM_MIN_PER_MM_S;

/** A speed per second (mm/s, °/s) as per minute (the unit of F). */
export const perMinute = (perS: number): number => perS * MM_MIN_PER_MM_S;

/** A parameter list's raw velocity (µm/s, 0.001°/s) in mm/min (°/min). */
export const rawVelocityPerMin = (raw: number): number => perMinute(raw * MM_PER_UM);
