// What rilbed run would refuse in a scenario object, as far as the page can tell (the run
// has the last word): robots, IDs and kinds, each robot's controller, parameters and
// sensors against the controller registry (controllers.json), overlaps, obstacles, tracks
// and beacons; the robots' `model:`, `body:` and `wheels:` (src/run/robot_description.cpp's
// rules; the model file itself is the run's to read). Each problem is a sentence naming the
// item.
import { formatIds } from './ids.js';
import { degToRad } from './angles.js';
import { outlineInField } from './body.js';
import { distToSegment, pointInPolygon, polygonOverlapsDisc, polygonsOverlap } from './geometry.js';
import { controllerLabel, numberText, rangeText, withUnit } from './controller_registry.js';
import {
  controllerRef, entryBody, entryIds, entryRadius, isNum, isPoint, listOf, obstaclePoints, robotHasSensor, robotItems,
  scenarioField, trackPoints,
} from './scenario.js';

// The problems of one value given for parameter spec `p` (none when it is fine).
export function paramValueProblems(p, value) {
  const key = `params.${p.name}`;
  if (typeof value !== 'number' || !isNum(value)) return [`${key} must be a number, not ${JSON.stringify(value)}`];
  if (p.integer && !Number.isInteger(value)) return [`${key} must be a whole number, not ${numberText(value)}`];
  if ((p.min !== null && value < p.min) || (p.max !== null && value > p.max)) {
    return [`${key} must be ${rangeText(p)}${withUnit(p)}, not ${numberText(value)}`];
  }
  return [];
}

// The problems of robot entry `e`'s `params` for controller entry `c`: names it does not
// take, values it would refuse, required ones missing.
export function paramsProblems(c, params) {
  if (params === undefined || params === null) params = {};
  if (typeof params !== 'object' || Array.isArray(params)) return ['params must be a mapping of names to numbers ({speed_mps: 0.08})'];
  const out = [];
  for (const [key, value] of Object.entries(params)) {
    const p = c.params.find((q) => q.name === key);
    if (!p) out.push(`controller ${c.name} has no parameter '${key}' (it takes ${c.params.map((q) => q.name).join(', ') || 'none'})`);
    else out.push(...paramValueProblems(p, value));
  }
  for (const p of c.params) {
    if (p.required && !(p.name in params)) out.push(`controller ${c.name} needs parameter '${p.name}' (${p.summary})`);
  }
  return out;
}

// The problems of a `controller: {library: PATH, name: NAME}` mapping's own keys, in the
// scenario parser's words: it takes those two, and needs both.
function controllerMappingProblems(v) {
  if ('python' in v) {
    // A Python class (`{python: FILE, class: NAME}`): the run imports the file and checks
    // the class and its params when it reads the scenario; the page cannot.
    const out = Object.keys(v).filter((k) => k !== 'python' && k !== 'class')
      .map((k) => `controller.${k}: unknown key (allowed here: python, class)`);
    if (typeof v.python !== 'string' || !v.python) out.push("controller.python: give the Python file's path, relative to the scenario file");
    if (typeof v.class !== 'string' || !v.class) out.push('controller.class: give the name of a class of the file that subclasses rilbed.Controller');
    return out;
  }
  const out = Object.keys(v).filter((k) => k !== 'library' && k !== 'name')
    .map((k) => `controller.${k}: unknown key (allowed here: library, name)`);
  if (typeof v.library !== 'string' || !v.library) out.push("controller.library: give the plug-in library's path, relative to the scenario file");
  if (typeof v.name !== 'string' || !v.name) out.push("controller.name: give the name of one of the library's controllers");
  return out;
}

// Why the registry has no entry for controller reference `ref` (scenario.js's controllerRef),
// naming what it does have: for a name alone, every controller; for a library's, the
// library's, or else the libraries there are.
function unknownController(ref, registry) {
  if (!ref.library) {
    const c = registry.find(ref.name);
    // (The parser's words: a name alone does not say which file to load it from.)
    if (c) return `'${ref.name}' comes from the plug-in library ${c.library}: name it as {library: PATH, name: ${ref.name}}`;
    return `unknown controller '${ref.name}' (rilbed knows ${registry.entries.map(controllerLabel).join(', ')})`;
  }
  const held = registry.fromLibrary(ref.library).map((c) => c.name);
  const others = registry.libraries;
  const known = held.length ? `it holds ${held.join(', ')}`
    : others.length ? `the registry has none of its controllers; its plug-in libraries: ${others.join(', ')}`
      : 'the registry has no plug-in library';
  return `unknown controller '${ref.name}' of plug-in library ${ref.library} (${known})`;
}

// The problems of robot entry `e` with the registry: a controller it does not have (by name,
// or of a plug-in library), its params, the sensors the controller requires.
export function controllerProblems(e, registry) {
  const v = e.controller;
  if (v && typeof v === 'object' && !Array.isArray(v)) {
    const shape = controllerMappingProblems(v);
    if (shape.length || 'python' in v) return shape;
  }
  const ref = controllerRef(e);
  if (!ref) return ["controller must be a controller's name or {library: PATH, name: NAME}"];
  const c = registry.match(ref);
  if (!c) return [unknownController(ref, registry)];
  const out = paramsProblems(c, e.params);
  for (const s of c.required_sensors) {
    if (!robotHasSensor(e.sensors, s)) out.push(`${c.name} needs sensors: ${s}`);
  }
  return out;
}

const isMapping = (v) => v !== null && typeof v === 'object' && !Array.isArray(v);
const MAX_OUTLINE_POINTS = 32; // environment/body_shape.hpp's kMaxOutlineVertices

// What is wrong with outline `pts` (3 to 32 [x, y] points) as the run checks it
// (checked_outline): null when it is fine.
function outlineProblem(pts) {
  const n = pts.length;
  let area2 = 0;
  for (let i = 0; i < n; ++i) area2 += pts[i][0] * pts[(i + 1) % n][1] - pts[(i + 1) % n][0] * pts[i][1];
  if (Math.abs(area2) / 2 < 1e-8) return 'has (almost) no area';
  const o = Math.sign(area2); // either way round
  let turning = 0;
  for (let i = 0; i < n; ++i) {
    const a = pts[(i + n - 1) % n], b = pts[i], c = pts[(i + 1) % n];
    const ux = b[0] - a[0], uy = b[1] - a[1], vx = c[0] - b[0], vy = c[1] - b[1];
    const cross = o * (ux * vy - uy * vx);
    if (cross < -1e-12) return 'is not convex';
    turning += Math.atan2(cross, ux * vx + uy * vy);
  }
  if (turning > 2 * Math.PI + 1e-6) return 'crosses itself';
  for (let i = 0; i < n; ++i) {
    const a = pts[i], b = pts[(i + 1) % n];
    if (o * ((b[0] - a[0]) * -a[1] - (b[1] - a[1]) * -a[0]) <= 1e-9) return "must hold the robot's centre (0, 0) strictly inside";
  }
  return null;
}

// The problems of robot entry `e`'s `model:`, `body:` and `wheels:`, in the scenario
// parser's words (without the entry's name).
export function bodyProblems(e) {
  const out = [];
  if (e.model !== undefined && (typeof e.model !== 'string' || !e.model.trim())) {
    out.push("model must name a robot model file (robots/epuck.yaml) or a shipped model's name (epuck)");
  }
  if (e.body !== undefined) {
    const b = e.body;
    if (!isMapping(b)) {
      out.push('body must be {radius_m: R} (a disc) or {outline_m: [[x, y], ...]} (a convex outline, robot frame)');
    } else {
      out.push(...Object.keys(b).filter((k) => k !== 'radius_m' && k !== 'outline_m')
        .map((k) => `body.${k}: unknown key (allowed here: radius_m, outline_m)`));
      if ('radius_m' in b && 'outline_m' in b) out.push('body: give either radius_m (a disc) or outline_m');
      if ('radius_m' in b) {
        if (!isNum(b.radius_m) || b.radius_m <= 0) out.push(`body.radius_m must be a number above 0, not ${JSON.stringify(b.radius_m)}`);
        else if (b.radius_m > 1) out.push("body.radius_m is at most 1 m (a robot on a lab's table)");
      }
      if ('outline_m' in b) {
        const pts = b.outline_m;
        if (!Array.isArray(pts)) {
          out.push('body.outline_m must be a list of [x, y] points (robot frame: x forward, y left, metres)');
        } else if (!pts.every(isPoint)) {
          out.push(`body.outline_m: point ${pts.findIndex((p) => !isPoint(p)) + 1} is not [x, y] (metres)`);
        } else if (pts.length < 3) {
          out.push(`body.outline_m needs at least 3 points, not ${pts.length}`);
        } else if (pts.length > MAX_OUTLINE_POINTS) {
          out.push(`body.outline_m has ${pts.length} points: at most ${MAX_OUTLINE_POINTS}`);
        } else {
          const why = outlineProblem(pts);
          if (why) out.push(`body.outline_m ${why}`);
          else if (Math.max(...pts.map(([x, y]) => Math.hypot(x, y))) > 1) out.push("body.outline_m reaches more than 1 m from the centre (a robot on a lab's table)");
        }
      }
    }
  }
  if (e.wheels !== undefined) {
    const w = e.wheels;
    if (!isMapping(w)) {
      out.push('wheels must be {base_m: B, radius_m: R}');
    } else {
      out.push(...Object.keys(w).filter((k) => k !== 'base_m' && k !== 'radius_m')
        .map((k) => `wheels.${k}: unknown key (allowed here: base_m, radius_m)`));
      for (const [k, max] of [['base_m', 2], ['radius_m', 0.5]]) {
        if (!(k in w)) continue;
        if (!isNum(w[k]) || w[k] <= 0) out.push(`wheels.${k} must be a number above 0, not ${JSON.stringify(w[k])}`);
        else if (w[k] > max) out.push(`wheels.${k} is at most ${max} m`);
      }
    }
  }
  return out;
}

function robotProblems(doc, registry) {
  const out = [];
  const robots = robotItems(doc);
  if (!robots.length) out.push('robots: rilbed run needs at least one robot.');
  const seen = new Set();
  for (const r of robots) {
    if (seen.has(r.id)) out.push(`robot ${r.id} is defined twice.`);
    seen.add(r.id);
  }
  listOf(doc, 'robots').forEach((e, i) => {
    if (!entryIds(e).length) out.push(`robots[${i}]: no valid id or ids.`);
    if (e?.kind === 'real' && !e.link) out.push(`robots[${i}]: a real robot needs a link.`);
    if (isMapping(e)) out.push(...bodyProblems(e).map((p) => `robots[${i}]: ${p}.`));
    if (registry && e && typeof e === 'object') out.push(...controllerProblems(e, registry).map((p) => `robots[${i}]: ${p}.`));
  });
  if (listOf(doc, 'robots').some((e) => e?.kind === 'real') && !doc.camera) out.push('camera: real robots need a camera.');
  // The convoy's own rule (scenarios/README.md): agent k follows agent k-1.
  const isConvoy = (ref) => ref?.name === 'convoy' && !ref.library;
  const convoy = robots.filter((r) => isConvoy(controllerRef(r.e))).map((r) => r.id).sort((a, b) => a - b);
  if (convoy.some((id, k) => id !== k + 1)) out.push(`convoy robots must be numbered 1..N; they are ${formatIds(convoy)}.`);
  return out;
}

const obstacleName = (o, i) => `obstacle ${i + 1}${o?.name ? ` (${o.name})` : ''}`;

// A placed robot's shape where it starts: its bounding disc (c, r) and, for an outline
// body, the outline in the field's frame (poly); a Khepera's disc without a body override
// (a model's body is the model file's: the page does not read it).
function placedShape(r) {
  const body = entryBody(r.e);
  const poly = body ? outlineInField(body, { x_m: r.x, y_m: r.y, theta_rad: degToRad(r.th) }) : null;
  return { id: r.id, c: [r.x, r.y], r: entryRadius(r.e), poly };
}
function shapesOverlap(a, b) {
  if (Math.hypot(a.c[0] - b.c[0], a.c[1] - b.c[1]) >= a.r + b.r) return false;
  if (a.poly && b.poly) return polygonsOverlap(a.poly, b.poly);
  if (a.poly) return polygonOverlapsDisc(a.poly, b.c, b.r);
  if (b.poly) return polygonOverlapsDisc(b.poly, a.c, a.r);
  return true;
}

function overlapProblems(doc) {
  const out = [];
  const F = scenarioField(doc), EPS = 1e-9;
  const placed = robotItems(doc).filter((r) => r.placed).map(placedShape);
  for (const s of placed) {
    const [x, y] = s.c;
    const outside = s.poly ? s.poly.some(([px, py]) => px < -EPS || py < -EPS || px > F.w + EPS || py > F.h + EPS)
      : x < s.r || y < s.r || x > F.w - s.r || y > F.h - s.r;
    if (F.walls && outside) out.push(`robot ${s.id} overlaps a wall.`);
    listOf(doc, 'obstacles').forEach((o, i) => {
      const pts = obstaclePoints(o);
      if (pointInPolygon(s.c, pts)) out.push(`robot ${s.id} is inside ${obstacleName(o, i)}.`);
      else if (s.poly ? pts.length >= 2 && polygonsOverlap(s.poly, pts) : pts.some((p, k) => distToSegment(s.c, p, pts[(k + 1) % pts.length]) < s.r)) {
        out.push(`robot ${s.id} overlaps ${obstacleName(o, i)}.`);
      }
    });
  }
  for (let i = 0; i < placed.length; ++i) {
    for (let j = i + 1; j < placed.length; ++j) {
      if (shapesOverlap(placed[i], placed[j])) out.push(`robots ${placed[i].id} and ${placed[j].id} overlap.`);
    }
  }
  return out;
}

function itemProblems(doc) {
  const out = [];
  listOf(doc, 'obstacles').forEach((o, i) => { if (obstaclePoints(o).length < 3) out.push(`obstacle ${i + 1} needs at least 3 points.`); });
  listOf(doc, 'tracks').forEach((t, i) => { if (trackPoints(t).length < 2) out.push(`track ${i + 1} needs at least 2 points.`); });
  const beaconIds = new Set();
  listOf(doc, 'beacons').forEach((b, i) => {
    if (beaconIds.has(b?.id)) out.push(`beacon ${b.id} is defined twice.`);
    beaconIds.add(b?.id);
    if (b?.aperture_deg !== undefined && !(b.aperture_deg > 0 && b.aperture_deg <= 360)) out.push(`beacon ${i + 1}: aperture_deg must be in (0, 360].`);
    if (b?.range_m !== undefined && !(b.range_m > 0)) out.push(`beacon ${i + 1}: range_m must be above 0.`);
  });
  return out;
}

// Every problem of scenario object `doc`. `registry` (a ControllerRegistry) checks the
// robots' controllers, parameters and sensors; without one (it did not load) they are not
// checked.
export function findProblems(doc, registry) {
  return [...robotProblems(doc, registry), ...overlapProblems(doc), ...itemProblems(doc)];
}
