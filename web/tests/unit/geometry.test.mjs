// Plane geometry (web/geometry.js) that the editor's hit tests and the checks rely on.
import test from 'node:test';
import assert from 'node:assert/strict';
import { centroid, distToSegment, pointInPolygon, polygonOverlapsDisc, polygonsOverlap, segmentsIntersect } from '../../geometry.js';

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

test('segmentsIntersect: crossing, apart, touching at an end, collinear overlapping or not', () => {
  assert.equal(segmentsIntersect([0, 0], [1, 1], [0, 1], [1, 0]), true);
  assert.equal(segmentsIntersect([0, 0], [1, 0], [0, 1], [1, 1]), false);
  assert.equal(segmentsIntersect([0, 0], [1, 0], [1, 0], [2, 5]), true);
  assert.equal(segmentsIntersect([0, 0], [2, 0], [1, 0], [3, 0]), true);
  assert.equal(segmentsIntersect([0, 0], [1, 0], [2, 0], [3, 0]), false);
});

test('polygonsOverlap: edges crossing, one inside the other, apart', () => {
  const moved = (dx, dy) => square.map(([x, y]) => [x + dx, y + dy]);
  assert.equal(polygonsOverlap(square, moved(0.5, 0.5)), true);
  assert.equal(polygonsOverlap(square, [[0.4, 0.4], [0.6, 0.4], [0.5, 0.6]]), true); // inside
  assert.equal(polygonsOverlap([[0.4, 0.4], [0.6, 0.4], [0.5, 0.6]], square), true);
  assert.equal(polygonsOverlap(square, moved(1.5, 0)), false);
  assert.equal(polygonsOverlap(square, []), false);
});

test('polygonOverlapsDisc: the centre inside, an edge nearer than the radius, or neither', () => {
  assert.equal(polygonOverlapsDisc(square, [0.5, 0.5], 0.01), true);
  assert.equal(polygonOverlapsDisc(square, [1.2, 0.5], 0.25), true);
  assert.equal(polygonOverlapsDisc(square, [1.2, 0.5], 0.15), false);
  assert.equal(polygonOverlapsDisc(square, [1.2, 1.2], 0.25), false); // past the corner: 0.28 away
});
