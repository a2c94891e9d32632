// Field metres <-> canvas pixels (web/projection.js): the live view's fit, camera, zoom and
// pan; the editor's layout above its tray.
import test from 'node:test';
import assert from 'node:assert/strict';
import { applyHomography, baseProjection, editorLayout, makeProjection, toField, toPx } from '../../projection.js';

const near = (a, b, tol = 1e-9) => assert.ok(Math.abs(a - b) <= tol, `${a} is not ${b} (within ${tol})`);
const nearPoint = (p, q, tol = 1e-9) => { near(p[0], q[0], tol); near(p[1], q[1], tol); };
const still = { zoom: 1, panX: 0, panY: 0 };
const field = { width_m: 1.5, height_m: 1.2 };

test('the live view fits the field within 16 px, centred, y up', () => {
  // 832 x 632 canvas: 800 x 600 px inside the margin; 1.5 x 1.2 m -> 500 px/m (the height binds).
  const P = makeProjection(832, 632, still, { field });
  assert.equal(P.base.s, 500);
  nearPoint(P.project(0, 0), [41, 616]);        // bottom left: (832 - 750) / 2 across, margin up from the bottom
  nearPoint(P.project(1.5, 1.2), [791, 16]);     // top right
  nearPoint(P.project(0.75, 0.6), [416, 316]);   // the centre of the canvas
  assert.equal(P.base.camera, false);
});

test('an unknown field is 1 x 1 m', () => {
  const P = makeProjection(232, 132, still, {});
  assert.equal(P.base.s, 100);
  nearPoint(P.project(1, 1), [166, 16]);
});

test('zoom and pan act on canvas pixels after the fit', () => {
  const P = makeProjection(832, 632, { zoom: 2, panX: -100, panY: 30 }, { field });
  nearPoint(P.project(0, 0), [-100 + 2 * 41, 30 + 2 * 616]);
  nearPoint(P.project(1.5, 1.2), [-100 + 2 * 791, 30 + 2 * 16]);
  near(P.scaleAt(0.3, 0.3), 1000, 1e-6);
});

test('the affine shortcut is the projection, and there is none with the camera', () => {
  const P = makeProjection(640, 480, { zoom: 1.7, panX: 12, panY: -8 }, { field });
  for (const [x, y] of [[0, 0], [0.3, 1.1], [1.5, 0.2]]) {
    nearPoint([P.affine.ax * x + P.affine.bx, P.affine.ay * y + P.affine.by], P.project(x, y));
  }
  const C = makeProjection(640, 480, still, { field, calibration: { width_px: 640, height_px: 480, field_to_image: [1, 0, 0, 0, 1, 0, 0, 0, 1] } });
  assert.equal(C.affine, null);
  assert.equal(C.base.camera, true);
});

test('with the camera image, field points go through the homography onto the fitted image', () => {
  // 100 px/m, image origin at field (0.5, 0.2), image v down: u = 100 x + 50, v = -100 y + 400 (w = 1).
  const H = [100, 0, 50, 0, -100, 400, 0, 0, 1];
  nearPoint(applyHomography(H, 1, 1), [150, 300]);
  // A 1280 x 960 image on a 640 x 720 canvas: scale 0.5, centred down (720 - 480) / 2 = 120.
  const calibration = { width_px: 1280, height_px: 960, field_to_image: H };
  const B = baseProjection(640, 720, { field, calibration });
  assert.deepEqual([B.s, B.ox, B.oy], [0.5, 0, 120]);
  const P = makeProjection(640, 720, still, { field, calibration });
  nearPoint(P.project(1, 1), [75, 270]);
  // A projective homography (w varies): the point is divided by w.
  nearPoint(applyHomography([2, 0, 0, 0, 2, 0, 0, 1, 1], 1, 1), [1, 1]);
});

test('onCanvas allows a margin around the canvas', () => {
  const P = makeProjection(100, 100, still, { field });
  assert.equal(P.onCanvas(50, 50, 0), true);
  assert.equal(P.onCanvas(-5, 50, 10), true);
  assert.equal(P.onCanvas(-15, 50, 10), false);
  assert.equal(P.onCanvas(50, 111, 10), false);
});

test('the editor fits the field above its tray and maps both ways', () => {
  // 1044 x 600 canvas, margin 22, tray 46: 1000 x 510 px for 1.5 x 1.2 m -> 425 px/m.
  const L = editorLayout(1044, 600, { w: 1.5, h: 1.2 }, { margin: 22, trayHeight: 46 });
  near(L.s, 425);
  near(L.ox, (1044 - 425 * 1.5) / 2);
  near(L.oy, 22 + 425 * 1.2);
  assert.equal(L.trayTop, 554);
  nearPoint(toPx(L, 0, 1.2), [L.ox, 22]);           // the field's top left at the margin
  nearPoint(toPx(L, 1.5, 0), [L.ox + 637.5, 532]);  // its bottom right just above the tray's margin
  for (const [x, y] of [[0, 0], [0.37, 1.01], [1.5, 1.2]]) nearPoint(toField(L, ...toPx(L, x, y)), [x, y], 1e-12);
});

test('the editor never has a scale of 0 or less (a hidden canvas)', () => {
  const L = editorLayout(0, 0, { w: 1.5, h: 1.2 }, { margin: 22, trayHeight: 46 });
  assert.ok(L.s > 0, `scale ${L.s}`);
});
