// Reading a scenario object (a parsed scenario YAML, scenarios/README.md) as rilbed run
// reads it: its field, its robot entries and their IDs, obstacles, tracks, sensors. The
// editor edits the object itself; these only look at it.
import { parseIds } from './ids.js';
import { robotBody } from './body.js';

export const ROBOT_RADIUS_M = 0.0275; // a Khepera
export const DEFAULT_FIELD = { width_m: 1.5, height_m: 1.2 };
// What a robot entry without `controller:` runs.
export const DEFAULT_CONTROLLER = 'convoy';

export const isNum = (v) => typeof v === 'number' && Number.isFinite(v);
export const isPoint = (p) => Array.isArray(p) && p.length === 2 && isNum(p[0]) && isNum(p[1]);
export const isPose = (p) => Array.isArray(p) && p.length === 3 && p.every(isNum);

// doc[key] when it is a list, else an empty one.
export const listOf = (doc, key) => (Array.isArray(doc?.[key]) ? doc[key] : []);

// The field: width w and height h in metres (the defaults when missing or not above 0),
// and whether it has walls.
export function scenarioField(doc) {
  const f = doc?.field && typeof doc.field === 'object' ? doc.field : {};
  return {
    w: isNum(f.width_m) && f.width_m > 0 ? f.width_m : DEFAULT_FIELD.width_m,
    h: isNum(f.height_m) && f.height_m > 0 ? f.height_m : DEFAULT_FIELD.height_m,
    walls: f.walls !== false,
  };
}

// A robot entry's IDs: its `id`, or those of its `ids`; none when they are not valid.
export function entryIds(e) {
  if (!e || typeof e !== 'object') return [];
  if (e.id !== undefined) return Number.isInteger(e.id) ? [e.id] : [];
  return parseIds(e.ids) || [];
}

// Every robot, one item per ID: {index (of its entry), id, placed, e (the entry)}, and for
// a placed one (one ID, a pose) its x, y and th (degrees); the others start at random poses.
export function robotItems(doc) {
  const out = [];
  listOf(doc, 'robots').forEach((e, index) => {
    const ids = entryIds(e);
    if (ids.length === 1 && isPose(e.pose)) {
      out.push({ index, id: ids[0], placed: true, x: e.pose[0], y: e.pose[1], th: e.pose[2], e });
    } else {
      for (const id of ids) out.push({ index, id, placed: false, e });
    }
  });
  return out;
}

export const obstaclePoints = (o) => (Array.isArray(o?.polygon) ? o.polygon.filter(isPoint) : []);
export const trackPoints = (t) => (Array.isArray(t?.points) ? t.points.filter(isPoint) : []);

const isText = (v) => typeof v === 'string' && v !== '';

// A robot entry's controller as {name, library}: a name alone (library null) names one of
// rilbed's own, `{library: PATH, name: NAME}` one of a plug-in library's, PATH as the file
// gives it (relative to the scenario file, or absolute). null when it names none: a list, or
// a mapping without both texts (scenario_checks.js says what is wrong with it).
export function controllerRef(e) {
  const v = e?.controller ?? DEFAULT_CONTROLLER;
  if (typeof v !== 'object') return { name: String(v), library: null };
  return !Array.isArray(v) && isText(v.library) && isText(v.name) ? { name: v.name, library: v.library } : null;
}

// What a robot entry's `controller:` says for registry entry `c`: its name, or for a
// plug-in library's controller the mapping the scenario parser asks for (a bare name would
// not tell rilbed run which file to load it from).
export const controllerValue = (c) => (c.library ? { library: c.library, name: c.name } : c.name);

// Whether a robot with this `sensors:` mapping has sensor `name` (a name of the registry's
// `sensors` lists), as robot_has_sensor decides: the IR ring and the odometer unless turned
// off, the pose always, a list (track, range_finders) when it has an element, any other
// when it is given.
export function robotHasSensor(sensors, name) {
  const given = sensors && typeof sensors === 'object' ? sensors[name] : undefined;
  if (name === 'pose') return true;
  if (name === 'proximity' || name === 'odometer') return given !== false;
  if (Array.isArray(given)) return given.length > 0;
  return given !== undefined && given !== null && given !== false;
}

// A robot entry's own body, from its `body:` override (a disc {radius_m: R}, or a convex
// outline {outline_m: [[x, y], ...]} in the robot's frame) and its `wheels:` ({base_m,
// radius_m}; what it leaves out is the Khepera's), as body.js draws it; null when it has
// none (or none that can be drawn): it is its model's (`model:`, a file the page does not
// read) or a Khepera's.
export function entryBody(e) {
  const b = e?.body;
  if (!b || typeof b !== 'object' || Array.isArray(b)) return null;
  const outline = Array.isArray(b.outline_m) ? b.outline_m.filter(isPoint) : [];
  if (outline.length < 3 && !(isNum(b.radius_m) && b.radius_m > 0)) return null;
  const w = e.wheels && typeof e.wheels === 'object' ? e.wheels : {};
  return robotBody({ radius_m: b.radius_m, outline_m: outline, wheel_base_m: w.base_m, wheel_radius_m: w.radius_m });
}

// The radius of a robot entry's bounding disc: its body override's, else a Khepera's.
export const entryRadius = (e) => entryBody(e)?.radius_m ?? ROBOT_RADIUS_M;

// The robot model a robot entry names (`model: robots/epuck.yaml`, or `epuck`), as a
// label shows it: the file's name without its folder and .yaml; null without one.
export function modelName(e) {
  const m = e?.model;
  if (typeof m !== 'string' || !m.trim()) return null;
  return m.trim().split('/').pop().replace(/\.ya?ml$/, '') || m.trim();
}
