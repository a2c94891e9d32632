// What rilbed run would refuse in a scenario object, as far as the page can tell (the run
// has the last word): robots, IDs and kinds, each robot's controller, parameters and
// sensors against the controller registry (controllers.json), overlaps, obstacles, tracks
// and beacons. Each problem is a sentence naming the item.
import { formatIds } from './ids.js';
import { distToSegment, pointInPolygon } from './geometry.js';
import { controllerLabel, numberText, rangeText, withUnit } from './controller_registry.js';
import {
  ROBOT_RADIUS_M, controllerRef, entryIds, isNum, listOf, obstaclePoints, robotHasSensor, robotItems, scenarioField,
  trackPoints,
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
    if (shape.length) return shape;
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

function overlapProblems(doc) {
  const out = [];
  const F = scenarioField(doc), R = ROBOT_RADIUS_M;
  const placed = robotItems(doc).filter((r) => r.placed);
  for (const r of placed) {
    if (F.walls && (r.x < R || r.y < R || r.x > F.w - R || r.y > F.h - R)) out.push(`robot ${r.id} overlaps a wall.`);
    listOf(doc, 'obstacles').forEach((o, i) => {
      const pts = obstaclePoints(o);
      if (pointInPolygon([r.x, r.y], pts)) out.push(`robot ${r.id} is inside ${obstacleName(o, i)}.`);
      else if (pts.some((p, k) => distToSegment([r.x, r.y], p, pts[(k + 1) % pts.length]) < R)) out.push(`robot ${r.id} overlaps ${obstacleName(o, i)}.`);
    });
  }
  for (let i = 0; i < placed.length; ++i) {
    for (let j = i + 1; j < placed.length; ++j) {
      if (Math.hypot(placed[i].x - placed[j].x, placed[i].y - placed[j].y) < 2 * R) out.push(`robots ${placed[i].id} and ${placed[j].id} overlap.`);
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
