// The sensor models' marks (web/marks.js): robot frame -> field frame with the robot's pose,
// and their 0xRRGGBBAA colours as CSS.
import test from 'node:test';
import assert from 'node:assert/strict';
import { marksInField, rgbaToCss, robotToField } from '../../marks.js';

const near = (a, b, tol = 1e-12) => assert.ok(Math.abs(a - b) <= tol, `${a} is not ${b} (within ${tol})`);
const nearPoint = (p, q, tol = 1e-12) => { near(p[0], q[0], tol); near(p[1], q[1], tol); };

test('robotToField: x forward and y left, turned by the heading counter-clockwise, then moved', () => {
  const still = { x_m: 0, y_m: 0, theta_rad: 0 };
  nearPoint(robotToField(still, 0.02, 0.012), [0.02, 0.012]);
  const north = { x_m: 0.75, y_m: 0.45, theta_rad: Math.PI / 2 }; // facing +y: forward is up, left is -x
  nearPoint(robotToField(north, 0.02, 0), [0.75, 0.47]);
  nearPoint(robotToField(north, 0, 0.012), [0.738, 0.45]);
  const south = { x_m: 0.75, y_m: 0.45, theta_rad: -Math.PI / 2 }; // 270 degrees, as track_following starts
  nearPoint(robotToField(south, 0.02, 0.012), [0.762, 0.43]);
  const diagonal = { x_m: 1, y_m: 1, theta_rad: Math.PI / 4 };
  nearPoint(robotToField(diagonal, Math.SQRT2, 0), [2, 2]);
  nearPoint(robotToField(diagonal, 0, Math.SQRT2), [0, 2]);
  nearPoint(robotToField(still, 0, 0), [0, 0]);
});

test('rgbaToCss: the bytes in order, alpha to [0, 1], colours above 0x7fffffff unsigned', () => {
  assert.equal(rgbaToCss(0x20c0f0ff), 'rgba(32,192,240,1)'); // the track sensor's
  assert.equal(rgbaToCss(0xff000080), 'rgba(255,0,0,0.502)'); // a red whose top bit is set
  assert.equal(rgbaToCss(0xffffffff), 'rgba(255,255,255,1)');
  assert.equal(rgbaToCss(0), 'rgba(0,0,0,0)');
  assert.equal(rgbaToCss(0x00ff0033), 'rgba(0,255,0,0.2)');
});

test('rgbaToCss: what is not a 32-bit colour is drawn opaque black', () => {
  for (const bad of [undefined, null, '0x20c0f0ff', -1, 0x100000000, 1.5, NaN]) {
    assert.equal(rgbaToCss(bad), 'rgba(0,0,0,1)', String(bad));
  }
});

test('marksInField: circles move with the robot and keep their radius; lines move both ends', () => {
  const pose = { x_m: 0.75, y_m: 0.45, theta_rad: Math.PI / 2 };
  const marks = [
    { shape: 'circle', x_m: 0.02, y_m: 0.012, radius_m: 0.004, x2_m: 0, y2_m: 0, rgba: 0x20c0f0ff },
    { shape: 'line', x_m: 0, y_m: 0, radius_m: 0, x2_m: 0.1, y2_m: -0.05, rgba: 0xff0000ff },
  ];
  const [circle, line] = marksInField(marks, pose);
  assert.equal(circle.shape, 'circle');
  nearPoint([circle.x_m, circle.y_m], [0.738, 0.47]);
  assert.equal(circle.radius_m, 0.004);
  assert.equal(circle.css, 'rgba(32,192,240,1)');
  assert.equal(line.shape, 'line');
  nearPoint([line.x_m, line.y_m], [0.75, 0.45]);
  nearPoint([line.x2_m, line.y2_m], [0.8, 0.55]);
  assert.equal(line.css, 'rgba(255,0,0,1)');
});

test('marksInField: none without marks or a pose; unknown shapes and bad numbers left out', () => {
  const pose = { x_m: 0, y_m: 0, theta_rad: 0 };
  assert.deepEqual(marksInField([], pose), []);
  assert.deepEqual(marksInField(undefined, pose), []); // a server from before marks
  assert.deepEqual(marksInField([{ shape: 'circle', x_m: 0, y_m: 0, radius_m: 0.01, rgba: 0 }], null), []);
  assert.deepEqual(marksInField([{ shape: 'circle', x_m: 0, y_m: 0, radius_m: 0.01, rgba: 0 }], { x_m: NaN, y_m: 0, theta_rad: 0 }), []);
  const kept = marksInField([
    { shape: 'square', x_m: 0, y_m: 0, radius_m: 0.01, rgba: 0 },
    { shape: 'circle', x_m: 0, y_m: null, radius_m: 0.01, rgba: 0 },
    { shape: 'circle', x_m: 0, y_m: 0, radius_m: 0, rgba: 0 },
    { shape: 'line', x_m: 0, y_m: 0, x2_m: Infinity, y2_m: 0, rgba: 0 },
    null,
    { shape: 'circle', x_m: 0.01, y_m: 0, radius_m: 0.002, rgba: 0x000000ff },
  ], pose);
  assert.equal(kept.length, 1);
  assert.deepEqual(kept[0], { shape: 'circle', x_m: 0.01, y_m: 0, radius_m: 0.002, css: 'rgba(0,0,0,1)' });
});
