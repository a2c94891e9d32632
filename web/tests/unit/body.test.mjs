// Robot bodies (web/body.js): /rilbed/world's `body` (or a scenario's override) made safe
// to draw, its outline, wheels and heading mark in the field's frame and on a canvas.
import test from 'node:test';
import assert from 'node:assert/strict';
import {
  HEADING_MARK, KHEPERA_BODY, WHEEL_WIDTH_M, bodyOnCanvas, headingEnd, outlineInField, reachAlong, robotBody, wheelsInField,
} from '../../body.js';
import { makeProjection } from '../../projection.js';

const near = (a, b, tol = 1e-12) => assert.ok(Math.abs(a - b) <= tol, `${a} is not ${b} (within ${tol})`);
const nearPoints = (ps, qs, tol = 1e-12) => {
  assert.equal(ps.length, qs.length, `${JSON.stringify(ps)} is not ${JSON.stringify(qs)}`);
  ps.forEach((p, i) => { near(p[0], qs[i][0], tol); near(p[1], qs[i][1], tol); });
};
const deg = (d) => (d * Math.PI) / 180;
// Twice the signed area: > 0 counter-clockwise in a y-up frame.
const area2 = (pts) => pts.reduce((a, [x, y], i) => { const [x2, y2] = pts[(i + 1) % pts.length]; return a + x * y2 - x2 * y; }, 0);

// robots/square.yaml as /rilbed/world sends it.
const SQUARE_WORLD = {
  name: 'square', radius_m: Math.hypot(0.035, 0.035),
  outline: [{ x_m: 0.035, y_m: 0.035 }, { x_m: -0.035, y_m: 0.035 }, { x_m: -0.035, y_m: -0.035 }, { x_m: 0.035, y_m: -0.035 }],
  wheel_base_m: 0.06, wheel_radius_m: 0.016,
};
const EPUCK_WORLD = { name: 'e-puck', radius_m: 0.035, outline: [], wheel_base_m: 0.053, wheel_radius_m: 0.0205 };

test('robotBody: no body is a Khepera II; a disc keeps its radius; an outline its points and bounding radius', () => {
  assert.equal(robotBody(undefined), KHEPERA_BODY);
  assert.equal(robotBody(null), KHEPERA_BODY);
  assert.deepEqual({ ...KHEPERA_BODY, outline: [...KHEPERA_BODY.outline] },
    { name: 'khepera2', radius_m: 0.0275, outline: [], wheel_base_m: 0.053, wheel_radius_m: 0.00764 });
  assert.deepEqual(robotBody(EPUCK_WORLD), { ...EPUCK_WORLD });
  const square = robotBody(SQUARE_WORLD);
  assert.deepEqual(square.outline, [[0.035, 0.035], [-0.035, 0.035], [-0.035, -0.035], [0.035, -0.035]]);
  near(square.radius_m, 0.0494974746830583, 1e-15);
  assert.equal(square.wheel_base_m, 0.06);
  assert.equal(square.wheel_radius_m, 0.016);
  // A scenario's override: points as [x, y], under outline_m.
  const wedge = robotBody({ outline_m: [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]] });
  assert.deepEqual(wedge.outline, [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]]);
  near(wedge.radius_m, 0.065);
  assert.equal(wedge.wheel_base_m, KHEPERA_BODY.wheel_base_m);
});

test('robotBody: what is missing or not a number is the Khepera\'s; an outline of fewer than 3 good points is the disc', () => {
  assert.deepEqual(robotBody({ radius_m: -1, wheel_base_m: 'wide', wheel_radius_m: 0 }), { ...KHEPERA_BODY, outline: [] });
  const two = robotBody({ radius_m: 0.04, outline: [{ x_m: 0.03, y_m: 0 }, { x_m: -0.03, y_m: 0 }, { x_m: NaN, y_m: 0 }] });
  assert.deepEqual(two.outline, []);
  assert.equal(two.radius_m, 0.04);
  assert.deepEqual(robotBody({ outline: 'square' }).outline, []);
});

test('reachAlong: a disc\'s radius every way; where a ray leaves an outline', () => {
  assert.equal(reachAlong(KHEPERA_BODY, deg(123)), 0.0275);
  const square = robotBody(SQUARE_WORLD);
  near(reachAlong(square, 0), 0.035, 1e-15);
  near(reachAlong(square, deg(90)), 0.035, 1e-15);
  near(reachAlong(square, deg(45)), Math.hypot(0.035, 0.035), 1e-15); // through a corner
  near(reachAlong(square, deg(-170)), 0.035 / Math.cos(deg(10)), 1e-15);
  const wedge = robotBody({ outline_m: [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]] });
  near(reachAlong(wedge, 0), 0.065, 1e-15);
  near(reachAlong(wedge, deg(180)), 0.025, 1e-15);
  // An outline not around its centre (the run refuses it): the bounding radius.
  const off = robotBody({ outline_m: [[0.1, 0.1], [0.2, 0.1], [0.2, 0.2]] });
  near(reachAlong(off, deg(180)), off.radius_m);
});

test('outlineInField: the outline turned by the heading and moved to the pose, in its order', () => {
  const square = robotBody(SQUARE_WORLD);
  assert.equal(outlineInField(KHEPERA_BODY, { x_m: 1, y_m: 1, theta_rad: 0 }), null);
  nearPoints(outlineInField(square, { x_m: 1, y_m: 2, theta_rad: 0 }), [[1.035, 2.035], [0.965, 2.035], [0.965, 1.965], [1.035, 1.965]]);
  // Facing +y: forward is up, left is -x.
  nearPoints(outlineInField(square, { x_m: 1, y_m: 2, theta_rad: deg(90) }), [[0.965, 2.035], [0.965, 1.965], [1.035, 1.965], [1.035, 2.035]], 1e-15);
  // 45 degrees: the corners on the axes, the front left one straight up.
  const d = Math.hypot(0.035, 0.035);
  nearPoints(outlineInField(square, { x_m: 0, y_m: 0, theta_rad: deg(45) }), [[0, d], [-d, 0], [0, -d], [d, 0]], 1e-15);
  const wedge = robotBody({ outline_m: [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]] });
  const turned = outlineInField(wedge, { x_m: 0.5, y_m: 0.5, theta_rad: deg(-90) }); // facing -y
  nearPoints(turned, [[0.5, 0.435], [0.535, 0.525], [0.465, 0.525]], 1e-15);
  assert.ok(area2(turned) > 0, 'a turn keeps the outline counter-clockwise');
});

test('wheelsInField: 2 x wheel radius along the heading, WHEEL_WIDTH_M across, at +-base/2 (left first)', () => {
  const [left, right] = wheelsInField(KHEPERA_BODY, { x_m: 0, y_m: 0, theta_rad: 0 });
  const w = WHEEL_WIDTH_M / 2, r = 0.00764, y = 0.0265;
  nearPoints(left, [[r, y + w], [-r, y + w], [-r, y - w], [r, y - w]], 1e-15);
  nearPoints(right, [[r, -y + w], [-r, -y + w], [-r, -y - w], [r, -y - w]], 1e-15);
  // The e-puck facing +y at (1, 1): its left wheel to the -x side, long along y.
  const [l2] = wheelsInField(robotBody(EPUCK_WORLD), { x_m: 1, y_m: 1, theta_rad: deg(90) });
  const xs = l2.map((p) => p[0]), ys = l2.map((p) => p[1]);
  near(Math.min(...xs), 1 - 0.0265 - w, 1e-15); near(Math.max(...xs), 1 - 0.0265 + w, 1e-15);
  near(Math.min(...ys), 1 - 0.0205, 1e-15); near(Math.max(...ys), 1 + 0.0205, 1e-15);
});

test('headingEnd: HEADING_MARK times the reach forward, straight ahead', () => {
  nearPoints([headingEnd(KHEPERA_BODY, { x_m: 0.5, y_m: 0.5, theta_rad: 0 })], [[0.5 + HEADING_MARK * 0.0275, 0.5]], 1e-15);
  nearPoints([headingEnd(robotBody(SQUARE_WORLD), { x_m: 0, y_m: 0, theta_rad: deg(90) })], [[0, HEADING_MARK * 0.035]], 1e-15);
});

test('bodyOnCanvas: the outline\'s points through the live view\'s projection, y turned down', () => {
  // A 1 x 1 m field on a 532 x 532 canvas: 500 px a metre, the origin at (16, 516).
  const P = makeProjection(532, 532, { zoom: 1, panX: 0, panY: 0 }, { field: { width_m: 1, height_m: 1 } });
  const square = robotBody(SQUARE_WORLD);
  const pose = { x_m: 0.5, y_m: 0.4, theta_rad: deg(30) };
  const d = bodyOnCanvas(square, pose, P.project, P.affine.ax);
  assert.equal(P.affine.ax, 500);
  nearPoints([d.centre], [[266, 316]], 1e-9);
  near(d.radius_px, 500 * square.radius_m, 1e-9);
  nearPoints(d.outline, outlineInField(square, pose).map(([x, y]) => [16 + 500 * x, 516 - 500 * y]), 1e-9);
  assert.ok(area2(d.outline) < 0, 'counter-clockwise in the field is clockwise on a y-down canvas');
  // Its front left corner: 45 degrees left of the heading, at the bounding radius.
  const a = deg(75);
  nearPoints([d.outline[0]], [[266 + 500 * square.radius_m * Math.cos(a), 316 - 500 * square.radius_m * Math.sin(a)]], 1e-9);
  assert.equal(d.wheels.length, 2);
  nearPoints(d.wheels[0], wheelsInField(square, pose)[0].map(([x, y]) => [16 + 500 * x, 516 - 500 * y]), 1e-9);
  const [hx, hy] = headingEnd(square, pose);
  nearPoints([d.heading], [[16 + 500 * hx, 516 - 500 * hy]], 1e-9);
});

test('bodyOnCanvas: a disc is its centre and radius; small bodies lose their outline, then their wheels', () => {
  const project = (x, y) => [100 * x, -100 * y];
  const e = bodyOnCanvas(robotBody(EPUCK_WORLD), { x_m: 1, y_m: 1, theta_rad: 0 }, project, 1000);
  assert.equal(e.outline, null);
  nearPoints([e.centre], [[100, -100]]);
  near(e.radius_px, 35, 1e-12);
  assert.equal(e.wheels.length, 2);
  const square = robotBody(SQUARE_WORLD);
  const far = bodyOnCanvas(square, { x_m: 0, y_m: 0, theta_rad: 0 }, project, 100); // 4.9 px: an outline, no wheels
  assert.equal(far.outline.length, 4);
  assert.equal(far.wheels, null);
  const farther = bodyOnCanvas(square, { x_m: 0, y_m: 0, theta_rad: 0 }, project, 40); // 2 px: a disc of 3
  assert.equal(farther.outline, null);
  assert.equal(farther.radius_px, 3);
});
