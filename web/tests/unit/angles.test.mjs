// Angle helpers (web/angles.js): wraps as src/core/geometry.hpp's, a scenario's headings.
import test from 'node:test';
import assert from 'node:assert/strict';
import { degToRad, headingDeg, radToDeg, wrapDeg180, wrapDeg360, wrapRadPi } from '../../angles.js';

const near = (a, b, tol = 1e-9) => assert.ok(Math.abs(a - b) <= tol, `${a} is not ${b} (within ${tol})`);

test('degrees and radians convert both ways', () => {
  near(degToRad(180), Math.PI);
  near(degToRad(-90), -Math.PI / 2);
  near(radToDeg(Math.PI / 4), 45);
  near(radToDeg(degToRad(123.4)), 123.4);
});

test('wrapDeg360 lands in [0, 360)', () => {
  assert.equal(wrapDeg360(0), 0);
  assert.equal(wrapDeg360(360), 0);
  assert.equal(wrapDeg360(-90), 270);
  assert.equal(wrapDeg360(725), 5);
  assert.equal(wrapDeg360(-725), 355);
  const tiny = wrapDeg360(-1e-15);
  assert.ok(tiny >= 0 && tiny < 360, `${tiny} is outside [0, 360)`);
});

test('wrapDeg180 lands in [-180, 180): 180 itself becomes -180', () => {
  assert.equal(wrapDeg180(180), -180);
  assert.equal(wrapDeg180(-180), -180);
  assert.equal(wrapDeg180(190), -170);
  assert.equal(wrapDeg180(-190), 170);
  assert.equal(wrapDeg180(45), 45);
  assert.equal(wrapDeg180(3 * 360 + 10), 10);
});

test('wrapRadPi lands in [-pi, pi)', () => {
  near(wrapRadPi(Math.PI), -Math.PI);
  near(wrapRadPi(3 * Math.PI / 2), -Math.PI / 2);
  near(wrapRadPi(-3 * Math.PI / 2), Math.PI / 2);
  near(wrapRadPi(0.5), 0.5);
  near(wrapRadPi(0.5 + 4 * Math.PI), 0.5, 1e-12);
});

test('headingDeg is a tenth of a degree in (-180, 180], never -0 nor -180', () => {
  assert.equal(headingDeg(190.34), -169.7);
  assert.equal(headingDeg(180), 180);
  assert.equal(headingDeg(-180), 180);
  assert.equal(headingDeg(-179.96), 180);
  assert.equal(headingDeg(179.96), 180);
  assert.equal(headingDeg(540), 180);
  assert.ok(Object.is(headingDeg(-0.01), 0), 'headingDeg(-0.01) is -0');
  assert.equal(headingDeg(12.345), 12.3);
  assert.equal(headingDeg(-45.06), -45.1);
});
