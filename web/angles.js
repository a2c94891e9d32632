// Angles as rilbed means them (src/core/geometry.hpp): radians on the wire (the run's
// messages), degrees in scenario files, both counter-clockwise from +x.

export const degToRad = (deg) => (deg * Math.PI) / 180;
export const radToDeg = (rad) => (rad * 180) / Math.PI;

// Degrees into [0, 360), as wrap_deg_360 (a tiny negative plus a turn can round up to 360).
export function wrapDeg360(deg) {
  if (deg >= 0 && deg < 360) return deg;
  const w = ((deg % 360) + 360) % 360;
  return w >= 360 ? w - 360 : w;
}

// Degrees into [-180, 180), as wrap_deg_180.
export const wrapDeg180 = (deg) => wrapDeg360(deg + 180) - 180;

// Radians into [-pi, pi), as wrap_rad_pi.
export const wrapRadPi = (rad) => degToRad(wrapDeg180(radToDeg(rad)));

// A heading as a scenario file is written with it: to a tenth of a degree, in (-180, 180]
// (a person writes 180, not -180), and never -0.
export function headingDeg(deg) {
  const r = Math.round(wrapDeg180(deg) * 10) / 10;
  if (r === -180) return 180;
  return r === 0 ? 0 : r;
}
