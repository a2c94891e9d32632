// Plane geometry (web/geometry.js) that the editor's hit tests and the checks rely on.
import test from 'node:test';
import assert from 'node:assert/strict';
import { centroid, distToSegment, pointInPolygon } from '../../geometry.js';

const square = [[0, 0], [1, 0], [1, 1], [0, 1]];

test('pointInPolygon: inside, outside, a concave polygon\'s notch', () => {
  assert.equal(pointInPolygon([0.5, 0.5], square), true);
  assert.equal(pointInPolygon([1.5, 0.5], square), false);
  assert.equal(pointInPolygon([0.5, -0.01], square), false);
  const u = [[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]]; // a U
  assert.equal(pointInPolygon([1.5, 2], u), false);
  assert.equal(pointInPolygon([0.5, 2], u), true);
  assert.equal(pointInPolygon([1.5, 0.5], u), true);
});

test('distToSegment: to the middle, beyond either end, a degenerate segment', () => {
  assert.equal(distToSegment([0.5, 2], [0, 0], [1, 0]), 2);
  assert.equal(distToSegment([-3, 4], [0, 0], [1, 0]), 5);
  assert.equal(distToSegment([4, 4], [0, 0], [1, 0]), 5);
  assert.equal(distToSegment([3, 4], [0, 0], [0, 0]), 5);
});

test('centroid is the mean of the points', () => {
  assert.deepEqual(centroid(square), [0.5, 0.5]);
  assert.deepEqual(centroid([[1, 2], [3, 6]]), [2, 4]);
});
