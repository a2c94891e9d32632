// Plane geometry on [x, y] points, for the editor's hit tests and the scenario checks
// (where robots with outlines overlap what).

// Whether point p lies inside the polygon `pts` (even-odd rule; its edges count either way).
export function pointInPolygon([x, y], pts) {
  let inside = false;
  for (let i = 0, j = pts.length - 1; i < pts.length; j = i++) {
    const [xi, yi] = pts[i], [xj, yj] = pts[j];
    if ((yi > y) !== (yj > y) && x < ((xj - xi) * (y - yi)) / (yj - yi) + xi) inside = !inside;
  }
  return inside;
}

// The distance from point p to the segment from a to b (a point when a is b).
export function distToSegment([px, py], [ax, ay], [bx, by]) {
  const dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
  const t = l2 ? Math.max(0, Math.min(1, ((px - ax) * dx + (py - ay) * dy) / l2)) : 0;
  return Math.hypot(px - ax - t * dx, py - ay - t * dy);
}

// The mean of the points (what a polygon or a track turns about).
export const centroid = (pts) => [pts.reduce((a, p) => a + p[0], 0) / pts.length, pts.reduce((a, p) => a + p[1], 0) / pts.length];

// Whether the segments from a to b and from c to d share a point (touching counts).
export function segmentsIntersect(a, b, c, d) {
  const cross = (o, p, q) => (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
  const d1 = cross(c, d, a), d2 = cross(c, d, b), d3 = cross(a, b, c), d4 = cross(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  const on = (o, p, q) => Math.min(o[0], p[0]) <= q[0] && q[0] <= Math.max(o[0], p[0]) && Math.min(o[1], p[1]) <= q[1] && q[1] <= Math.max(o[1], p[1]);
  return (d1 === 0 && on(c, d, a)) || (d2 === 0 && on(c, d, b)) || (d3 === 0 && on(a, b, c)) || (d4 === 0 && on(a, b, d));
}

// Whether polygons `p` and `q` overlap: an edge of one crosses an edge of the other, or one
// lies inside the other.
export function polygonsOverlap(p, q) {
  if (!p.length || !q.length) return false;
  for (let i = 0; i < p.length; ++i) {
    for (let j = 0; j < q.length; ++j) {
      if (segmentsIntersect(p[i], p[(i + 1) % p.length], q[j], q[(j + 1) % q.length])) return true;
    }
  }
  return pointInPolygon(p[0], q) || pointInPolygon(q[0], p);
}

// Whether polygon `pts` and the disc of radius r about point c overlap.
export function polygonOverlapsDisc(pts, c, r) {
  return pointInPolygon(c, pts) || pts.some((p, k) => distToSegment(c, p, pts[(k + 1) % pts.length]) < r);
}
