// Field metres <-> canvas pixels. The field's frame has x right and y up, in metres; a
// canvas has u right and v down, in CSS pixels. The live view (app.js) fits the field, or
// the camera image, to its canvas and then zooms and pans; the editor (editor.js) fits the
// field above its tray.

const LIVE_MARGIN_PX = 16; // around the field in the live view without the camera image

// Field point (x, y) through homography H (the calibration's field_to_image, row-major
// 3 x 3 as 9 numbers): the image pixel [u, v].
export function applyHomography(H, x, y) {
  const w = H[6] * x + H[7] * y + H[8];
  return [(H[0] * x + H[1] * y + H[2]) / w, (H[3] * x + H[4] * y + H[5]) / w];
}

// The live view before zoom and pan: canvas = (ox + s * u, oy + s * v) of base point
// toPx(x, y). With `calibration` (the camera image shown), the image fitted to the canvas
// and field points through its homography; without, the field (`field`: width_m and
// height_m, 1 m each when unknown) fitted within a margin, y turned up.
export function baseProjection(width, height, { field = null, calibration = null } = {}) {
  if (calibration) {
    const s = Math.min(width / calibration.width_px, height / calibration.height_px);
    const ox = (width - s * calibration.width_px) / 2, oy = (height - s * calibration.height_px) / 2;
    const H = calibration.field_to_image;
    return { s, ox, oy, camera: true, toPx: (x, y) => applyHomography(H, x, y) };
  }
  const fw = field?.width_m || 1, fh = field?.height_m || 1;
  const s = Math.min((width - 2 * LIVE_MARGIN_PX) / fw, (height - 2 * LIVE_MARGIN_PX) / fh);
  const ox = (width - s * fw) / 2, oy = (height + s * fh) / 2;
  return { s, ox, oy, camera: false, toPx: (x, y) => [x, -y] };
}

// Where field point (x, y) metres lands on a width x height canvas: the base projection
// (`scene`: as baseProjection takes it), then the view's zoom and pan (`view`: zoom, panX,
// panY).
export function makeProjection(width, height, view, scene = {}) {
  const base = baseProjection(width, height, scene);
  const z = view.zoom;
  const project = (x, y) => {
    const [u, v] = base.toPx(x, y);
    return [view.panX + z * (base.ox + base.s * u), view.panY + z * (base.oy + base.s * v)];
  };
  // Metres to pixels near a point (for radii): the projection's local scale.
  const scaleAt = (x, y) => {
    const [a, b] = project(x, y), [c, d] = project(x + 0.01, y);
    return Math.hypot(c - a, d - b) / 0.01;
  };
  // Without the camera the projection is u = ax * x + bx, v = ay * y + by: the loops over
  // thousands of points (trails) use that, allocating nothing.
  const affine = base.camera ? null
    : { ax: z * base.s, bx: view.panX + z * base.ox, ay: -z * base.s, by: view.panY + z * base.oy };
  // Whether canvas point (u, v) is within `margin` pixels of the canvas (else not drawn).
  const onCanvas = (u, v, margin) => u > -margin && v > -margin && u < width + margin && v < height + margin;
  return { project, scaleAt, base, z, affine, onCanvas, width, height };
}

// The editor's canvas: the field (`field`: w and h in metres) as large as fits within
// `margin` pixels, centred across, at the top, with a tray `trayHeight` pixels high under
// it. Scale s px/m, (ox, oy) where the field's origin lands, trayTop where the tray starts.
export function editorLayout(width, height, field, { margin, trayHeight }) {
  const s = Math.max(1e-6, Math.min((width - 2 * margin) / field.w, (height - trayHeight - 2 * margin) / field.h));
  const ox = (width - s * field.w) / 2, oy = margin + s * field.h;
  return { w: width, h: height, s, ox, oy, trayTop: height - trayHeight };
}

// Field metres -> canvas pixels, and back, on an editorLayout.
export const toPx = (L, x, y) => [L.ox + L.s * x, L.oy - L.s * y];
export const toField = (L, u, v) => [(u - L.ox) / L.s, (L.oy - v) / L.s];
