// A robot's body as the panel draws it: a disc, or a convex outline in the robot's frame
// (x forward, y left, metres, around the robot's centre, its wheel axle's middle), and its
// two wheels. The live view (app.js) takes each robot's from /rilbed/world's `body`
// ({name, radius_m, outline: [{x_m, y_m}, ...], wheel_base_m, wheel_radius_m}; none: a
// Khepera II); the editor (editor.js, through scenario.js) from a scenario entry's `body:`
// and `wheels:` overrides. Here: the body made safe to draw, and its shapes in the field's
// frame and on a canvas, for any projection.
import { robotToField } from './marks.js';

// What a robot without a body is (robots/khepera2.yaml, src/run/run_observer.hpp's BodyDrawing).
export const KHEPERA_BODY = Object.freeze({
  name: 'khepera2', radius_m: 0.0275, outline: Object.freeze([]), wheel_base_m: 0.053, wheel_radius_m: 0.00764,
});
// How wide a wheel is drawn (the Foxglove scene's wheels are 4 mm thick too).
export const WHEEL_WIDTH_M = 0.004;
// The heading mark reaches this far beyond the body's front (times its reach forward).
export const HEADING_MARK = 1.2;

const finite = (...xs) => xs.every(Number.isFinite);
const positive = (v) => (Number.isFinite(v) && v > 0 ? v : null);

// A body as drawn: {name, radius_m (for an outline, its bounding radius: its farthest
// vertex), outline ([[x, y], ...], robot frame; empty: the disc), wheel_base_m,
// wheel_radius_m}. `b` as /rilbed/world gives it (outline points as {x_m, y_m}) or with
// points as [x, y]; what is missing or not a number is the Khepera's; an outline of fewer
// than 3 good points is none (the disc).
export function robotBody(b) {
  if (!b || typeof b !== 'object') return KHEPERA_BODY;
  const points = Array.isArray(b.outline) ? b.outline : Array.isArray(b.outline_m) ? b.outline_m : [];
  let outline = points.map((p) => (Array.isArray(p) ? [p[0], p[1]] : [p?.x_m, p?.y_m])).filter(([x, y]) => finite(x, y));
  if (outline.length < 3) outline = [];
  const radius = outline.length ? Math.max(...outline.map(([x, y]) => Math.hypot(x, y)))
    : positive(b.radius_m) ?? KHEPERA_BODY.radius_m;
  return {
    name: typeof b.name === 'string' && b.name ? b.name : KHEPERA_BODY.name,
    radius_m: radius,
    outline,
    wheel_base_m: positive(b.wheel_base_m) ?? KHEPERA_BODY.wheel_base_m,
    wheel_radius_m: positive(b.wheel_radius_m) ?? KHEPERA_BODY.wheel_radius_m,
  };
}

// How far the body reaches from its centre along robot-frame direction `angle` (radians,
// counter-clockwise from forward): a disc's radius; where the ray leaves the outline (the
// nearest crossing; the bounding radius should the ray miss it, an outline not around its
// centre).
export function reachAlong(body, angle) {
  const o = body.outline;
  if (!o.length) return body.radius_m;
  const dx = Math.cos(angle), dy = Math.sin(angle);
  let best = Infinity;
  for (let i = 0; i < o.length; ++i) {
    const [ax, ay] = o[i], [bx, by] = o[(i + 1) % o.length];
    const ex = bx - ax, ey = by - ay;
    const den = dx * ey - dy * ex; // the ray (t d) meets a + s e where t d = a + s e
    if (Math.abs(den) < 1e-15) continue;
    const t = (ax * ey - ay * ex) / den, s = (ax * dy - ay * dx) / den;
    if (t > 0 && s >= -1e-12 && s <= 1 + 1e-12 && t < best) best = t;
  }
  return Number.isFinite(best) ? best : body.radius_m;
}

// The outline in the field's frame for a robot at `pose` ({x_m, y_m, theta_rad}): [[x, y],
// ...], counter-clockwise as given; null for a disc.
export function outlineInField(body, pose) {
  if (!body.outline.length) return null;
  return body.outline.map(([x, y]) => robotToField(pose, x, y));
}

// The two wheels in the field's frame: each a rectangle of 4 corners, 2 * wheel_radius_m
// long along the heading and WHEEL_WIDTH_M wide, centred at +-wheel_base_m / 2 across the
// axle (left wheel first).
export function wheelsInField(body, pose) {
  const r = body.wheel_radius_m, w = WHEEL_WIDTH_M / 2;
  return [1, -1].map((side) => {
    const y = (side * body.wheel_base_m) / 2;
    return [[r, y + w], [-r, y + w], [-r, y - w], [r, y - w]].map(([fx, fy]) => robotToField(pose, fx, fy));
  });
}

// The heading mark's far end in the field's frame: HEADING_MARK times the body's reach
// forward, straight ahead of the centre.
export function headingEnd(body, pose) {
  return robotToField(pose, HEADING_MARK * reachAlong(body, 0), 0);
}

// The robot as a canvas shows it, through `project` ((x, y) field metres -> [u, v] canvas
// pixels) at `pxPerM` pixels a metre near the robot: {centre: [u, v], radius_px (its
// bounding disc, at least minRadiusPx), outline: [[u, v], ...] or null (a disc of
// radius_px), wheels: two [[u, v] x 4] or null, heading: [u, v] (the mark's end)}. A body
// whose bounding disc is under outlinePx pixels is drawn as a disc, and without wheels
// under wheelsPx: too small to tell apart.
export function bodyOnCanvas(body, pose, project, pxPerM, { minRadiusPx = 3, outlinePx = 4, wheelsPx = 6 } = {}) {
  const centre = project(pose.x_m, pose.y_m);
  const exact = body.radius_m * pxPerM;
  const radiusPx = Math.max(minRadiusPx, exact);
  const toCanvas = (pts) => pts.map(([x, y]) => project(x, y));
  const outline = body.outline.length && exact >= outlinePx ? toCanvas(outlineInField(body, pose)) : null;
  const wheels = exact >= wheelsPx ? wheelsInField(body, pose).map(toCanvas) : null;
  const mark = headingEnd(body, pose);
  return { centre, radius_px: radiusPx, outline, wheels, heading: project(mark[0], mark[1]) };
}
