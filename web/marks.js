// The shapes a sensor model plug-in draws (the `marks` of a robot on /rilbed/sensors, paper
// 000 §8.3's "two small concentric circles when the track is detected"), made ready for the
// live view: the run sends them in the robot's frame (metres, x forward, y left) so that
// they follow the robot; the view needs them in the field's frame, coloured for a canvas.

// Robot-frame point (fx forward, fy left) of a robot at `pose` ({x_m, y_m, theta_rad}: field
// frame, heading counter-clockwise from +x): the field point [x, y].
export function robotToField(pose, fx, fy) {
  const c = Math.cos(pose.theta_rad), s = Math.sin(pose.theta_rad);
  return [pose.x_m + c * fx - s * fy, pose.y_m + s * fx + c * fy];
}

const FALLBACK_CSS = 'rgba(0,0,0,1)'; // a colour the run did not say: drawn, but plainly

// 0xRRGGBBAA, an integer as the run sends it, as CSS. Taken unsigned (>>>): a colour at or
// above 0x80000000 (any red from 128 up) would turn negative under JavaScript's signed
// 32-bit shifts. The alpha to 3 decimals, which is finer than its 256 steps.
export function rgbaToCss(rgba) {
  if (!Number.isInteger(rgba) || rgba < 0 || rgba > 0xffffffff) return FALLBACK_CSS;
  const u = rgba >>> 0;
  const a = Number(((u & 0xff) / 255).toFixed(3));
  return `rgba(${u >>> 24},${(u >>> 16) & 0xff},${(u >>> 8) & 0xff},${a})`;
}

const finite = (...xs) => xs.every(Number.isFinite);

// A robot's marks in the field's frame for a robot at `pose`: circles as {shape: 'circle',
// x_m, y_m, radius_m, css} (a turn moves a circle's centre, not its radius), lines as
// {shape: 'line', x_m, y_m, x2_m, y2_m, css}. A mark of another shape, or with a coordinate
// that is not a number, is left out rather than drawn somewhere wrong.
export function marksInField(marks, pose) {
  const out = [];
  if (!Array.isArray(marks) || !pose || !finite(pose.x_m, pose.y_m, pose.theta_rad)) return out;
  for (const m of marks) {
    if (m?.shape === 'circle' && finite(m.x_m, m.y_m, m.radius_m) && m.radius_m > 0) {
      const [x, y] = robotToField(pose, m.x_m, m.y_m);
      out.push({ shape: 'circle', x_m: x, y_m: y, radius_m: m.radius_m, css: rgbaToCss(m.rgba) });
    } else if (m?.shape === 'line' && finite(m.x_m, m.y_m, m.x2_m, m.y2_m)) {
      const [x, y] = robotToField(pose, m.x_m, m.y_m), [x2, y2] = robotToField(pose, m.x2_m, m.y2_m);
      out.push({ shape: 'line', x_m: x, y_m: y, x2_m: x2, y2_m: y2, css: rgbaToCss(m.rgba) });
    }
  }
  return out;
}
