// rilbed's scenario editor: place, move, rotate and delete robots, obstacles, tracks and
// beacons on a canvas of the field, and save the scenario YAML that `rilbed run` reads
// (scenarios/README.md is the contract). The controllers, their parameters and the sensors
// they need come from the server's registry (controllers.json), never from a list here:
// rilbed's own, named by name, and those of the run's plug-in libraries, named
// `{library: PATH, name: NAME}`.
//
// The editor edits the parsed YAML object itself (`ed.doc`), never a model of its own:
// whatever it does not show (camera, safety, sensors, a real robot's link, moving
// obstacles, `ids: 4-5` ranges...) is saved as it was loaded. A robot of an
// `ids:` group with a random pose sits in the tray under the field; dragging it onto the
// field takes it out of its group as an entry of its own with that pose.
//
// "Start from this run" builds a scenario from what the live page holds (app.js's
// window.rilbed.run: /rilbed/world and /rilbed/poses); "Poses from run" puts the run's
// current poses into the scenario being edited.
//
// A robot entry's `model:`, `body:` and `wheels:` are kept as loaded. One with a `body:`
// override is drawn as that body (its disc, or its outline turned to its heading), and hit
// and checked by it; one with a `model:` alone is drawn as a Khepera (the page does not
// read model files), its label naming the model.
import { prepareCanvas } from './canvas.js';
import { degToRad, headingDeg, radToDeg } from './angles.js';
import { KHEPERA_BODY, bodyOnCanvas, robotBody } from './body.js';
import { centroid, distToSegment, pointInPolygon } from './geometry.js';
import { formatIds, parseIds } from './ids.js';
import { editorLayout, toField, toPx } from './projection.js';
import { controllerLabel, controllerTitle, loadRegistry, numberText, paramDescription } from './controller_registry.js';
import {
  DEFAULT_CONTROLLER, DEFAULT_FIELD, ROBOT_RADIUS_M, controllerRef, controllerValue, entryBody, entryIds, entryRadius, isNum,
  isPoint, isPose, listOf, modelName, obstaclePoints, robotHasSensor, robotItems as robotItemsOf, scenarioField, trackPoints,
} from './scenario.js';
import { findProblems as scenarioProblems } from './scenario_checks.js';
import { readScenarioText, scenarioText as yamlText } from './scenario_yaml.js';

const $ = (id) => document.getElementById(id);

// What the editor adds to a robot's `sensors:` when its new controller requires a sensor it
// lacks (keyed by sensor, as the registry's required_sensors name them): track elements
// three across its front, as in scenarios/track_following.yaml; an all-round beacon finder;
// one ultrasonic finder ahead; the IR ring and odometer turned back on.
const DEFAULT_SENSORS = {
  track: [0.012, 0, -0.012].map((y) => ({
    mount_x_m: 0.02, mount_y_m: y, height_mm: 8, inclination_deg: 0, cone_angle_deg: 30, precision: 16,
    coverage_percent: 15, max_value: 255, error_level_percent: 5,
  })),
  beacon_finder: { field_of_view_deg: 360 },
  range_finders: [{ mount_deg: 0, opening_deg: 30, max_range_m: 1.0 }],
  proximity: true,
  odometer: true,
};
const TRAY_HEIGHT_PX = 46;
const MARGIN_PX = 22;
const HANDLE_PX = 7;
const UNDO_DEPTH = 100;

// ------------------------------------------------------------------ state
const ed = {
  doc: null,                // the scenario object: what is saved
  header: '',               // the loaded file's leading comment lines, kept on save
  tool: 'select',
  sel: null,                // {type: robot|obstacle|track|beacon, index, id?, tray?, vertex?}
  draft: null,              // {type: obstacle|track, points: [[x, y], ...]} while drawing
  drag: null,
  mouse: null,              // [u, v] on the canvas
  undo: [], redo: [],
  yaml: '',
};

// The controllers a robot can have: the server's registry (controllers.json), which the
// scenario parser checks against too. The editor has no list of its own: until the
// registry has come there is no controller to choose, and if it fails to come the page says
// so and the robots' controllers go unchecked.
const controllers = { registry: null, error: null, loaded: false };

const canvas = $('editor-canvas');
const ctx = canvas.getContext('2d');

// ------------------------------------------------------------------ numbers
const round3 = (v) => { const r = Math.round(v * 1000) / 1000; return r === 0 ? 0 : r; };
const snapOn = () => $('editor-snap').checked;
const snap = (v) => (snapOn() ? Math.round(v * 100) / 100 : round3(v));
const clone = (v) => (v === undefined ? undefined : JSON.parse(JSON.stringify(v)));

// A copy of `obj` with key `from` replaced by `to` (value `value`) in the same place.
function renameKey(obj, from, to, value) {
  const out = {};
  for (const [k, v] of Object.entries(obj)) {
    if (k === from) out[to] = value; else if (k !== to) out[k] = v;
  }
  if (!(from in obj)) out[to] = value;
  return out;
}

// ------------------------------------------------------------------ the scenario's items
const list = (key) => listOf(ed.doc, key);
const field = () => scenarioField(ed.doc);
function ensureList(key) {
  if (!Array.isArray(ed.doc[key])) ed.doc[key] = [];
  return ed.doc[key];
}

// Every robot: placed ones (one id, a pose) and the tray's (random poses).
const robotItems = () => robotItemsOf(ed.doc);
const nextRobotId = () => Math.max(0, ...robotItems().map((r) => r.id)) + 1;
const nextBeaconId = () => Math.max(0, ...list('beacons').map((b) => (Number.isInteger(b?.id) ? b.id : 0))) + 1;
function uniqueName(key, stem) {
  const names = new Set(list(key).map((x) => x?.name));
  for (let k = list(key).length + 1; ; ++k) if (!names.has(`${stem}${k}`)) return `${stem}${k}`;
}

// ------------------------------------------------------------------ YAML
// What is saved: the document in the shipped scenarios' style, after the loaded file's header.
const scenarioText = () => yamlText(ed.doc, ed.header);

// ------------------------------------------------------------------ changes and undo
function checkpoint() {
  ed.undo.push(JSON.stringify(ed.doc));
  if (ed.undo.length > UNDO_DEPTH) ed.undo.shift();
  ed.redo = [];
  updateButtons();
}
function undo(back = true) {
  const from = back ? ed.undo : ed.redo, to = back ? ed.redo : ed.undo;
  if (!from.length) return;
  to.push(JSON.stringify(ed.doc));
  ed.doc = JSON.parse(from.pop());
  ed.sel = null; ed.draft = null;
  syncScenarioInputs();
  changed(true);
  status(back ? 'Undone.' : 'Redone.');
}
// After any change of the document: redraw, the form, the problems, the YAML.
function changed(rebuildForm = false) {
  if (rebuildForm) renderForm(); else refreshForm();
  ed.yaml = scenarioText();
  $('editor-yaml').value = ed.yaml;
  showProblems();
  updateButtons();
  requestDraw();
}
function setDoc(doc, header, message) {
  ed.doc = doc; ed.header = header || '';
  ed.undo = []; ed.redo = []; ed.sel = null; ed.draft = null;
  setTool('select');
  syncScenarioInputs();
  changed(true);
  status(message);
}
function status(message, bad = false) {
  const s = $('editor-status');
  s.textContent = message || '';
  s.classList.toggle('editor-bad', bad);
}
function updateButtons() {
  $('editor-undo').disabled = !ed.undo.length;
  $('editor-redo').disabled = !ed.redo.length;
  $('editor-delete').disabled = !ed.sel;
}

// ------------------------------------------------------------------ edits
function setPose(e, pose) { e.pose = [round3(pose[0]), round3(pose[1]), headingDeg(pose[2])]; }

// Gives robot `id` of entry `index` a pose; an `ids:` group gives the robot up to an entry
// of its own right after it. Returns the robot's entry index.
function placeRobot(index, id, x, y, th) {
  const robots = ensureList('robots');
  const e = robots[index];
  const ids = entryIds(e);
  if (ids.length <= 1) { setPose(e, [x, y, th]); return index; }
  const single = {};
  for (const [k, v] of Object.entries(e)) {
    if (k === 'ids') single.id = id; else if (k !== 'pose') single[k] = clone(v); else single.pose = null;
  }
  setPose(single, [x, y, th]);
  const rest = ids.filter((k) => k !== id);
  robots[index] = rest.length === 1 ? renameKey(e, 'ids', 'id', rest[0]) : renameKey(e, 'ids', 'ids', formatIds(rest));
  // Before its group when it was the group's first, else after: entries stay in ID order.
  const at = id < rest[0] ? index : index + 1;
  robots.splice(at, 0, single);
  return at;
}
// Takes robot `id` out of entry `index` (the whole entry when it is its only robot).
function removeRobot(index, id) {
  const robots = ensureList('robots');
  const rest = entryIds(robots[index]).filter((k) => k !== id);
  if (!rest.length) robots.splice(index, 1);
  else robots[index] = rest.length === 1 ? renameKey(robots[index], 'ids', 'id', rest[0]) : renameKey(robots[index], 'ids', 'ids', formatIds(rest));
}
// Entry e runs registry entry `c`: a plug-in library's named {library, name} with the
// registry's absolute path, which holds wherever the file is saved. A controller given a
// parameter it does not take stops the run, so a change of controller drops them; a sensor
// the new controller requires is added with its defaults.
function setController(e, c) {
  e.controller = controllerValue(c);
  dropParamsNotTaken(e, c);
  addRequiredSensors(e, c);
}
function dropParamsNotTaken(e, c) {
  if (!e.params || typeof e.params !== 'object') return;
  for (const k of Object.keys(e.params)) if (!c?.params.some((p) => p.name === k)) delete e.params[k];
  if (!Object.keys(e.params).length) delete e.params;
}
function addRequiredSensors(e, c) {
  const missing = (c?.required_sensors ?? []).filter((s) => !robotHasSensor(e.sensors, s) && s in DEFAULT_SENSORS);
  if (!missing.length) return;
  if (!e.sensors || typeof e.sensors !== 'object') e.sensors = {};
  for (const s of missing) e.sensors[s] = clone(DEFAULT_SENSORS[s]);
}
// Parameter `name` of entry e set to `value`, or removed (null: its default applies).
function setParam(e, name, value) {
  if (value === null) {
    if (e.params && typeof e.params === 'object') delete e.params[name];
    if (e.params && !Object.keys(e.params).length) delete e.params;
    return;
  }
  if (!e.params || typeof e.params !== 'object' || Array.isArray(e.params)) putKey(e, 'params', {}, ['controller', 'pose', 'link', 'kind', 'id', 'ids']);
  e.params[name] = value;
}
const stashedLinks = new WeakMap(); // an entry made virtual keeps its link here, should it be made real again
// Sets obj[key] in place, placed after the first of `after` that obj has (else before
// `before`, else last), so that a key the editor adds reads where a person would write it.
function putKey(obj, key, value, after = [], before = null) {
  const entries = Object.entries(obj).filter(([k]) => k !== key);
  let i = -1;
  for (const a of after) { i = entries.findIndex(([k]) => k === a); if (i >= 0) { i += 1; break; } }
  if (i < 0 && before) i = entries.findIndex(([k]) => k === before);
  if (i < 0) i = entries.length;
  entries.splice(i, 0, [key, value]);
  for (const k of Object.keys(obj)) delete obj[k];
  for (const [k, v] of entries) obj[k] = v;
}
function setKind(index, kind) {
  const e = ensureList('robots')[index];
  if (kind === 'real') {
    putKey(e, 'kind', 'real', ['id', 'ids']);
    if (!e.link) putKey(e, 'link', stashedLinks.get(e) || { emulate: true }, ['kind']);
    if (!ed.doc.camera) putKey(ed.doc, 'camera', { emulate: true }, [], 'robots');
  } else {
    if (e.link) stashedLinks.set(e, e.link);
    delete e.link;
    if (e.kind !== undefined) e.kind = 'virtual';
  }
}
function newRobot(x, y) {
  const idWanted = Number($('editor-new-robot-id').value);
  const taken = new Set(robotItems().map((r) => r.id));
  const id = Number.isInteger(idWanted) && idWanted >= 1 && !taken.has(idWanted) ? idWanted : nextRobotId();
  const e = { id };
  if ($('editor-new-kind').value === 'real') e.kind = 'real';
  e.pose = null;
  setPose(e, [x, y, Number($('editor-new-robot-theta').value) || 0]);
  const controller = controllers.registry?.find($('editor-new-controller').value);
  if (controller) setController(e, controller); // (none to choose when the list did not load: the scenario's default)
  const robots = ensureList('robots');
  robots.push(e);
  if (e.kind === 'real') setKind(robots.length - 1, 'real');
  $('editor-new-robot-id').value = '';
  return robots.length - 1;
}
function newBeacon(x, y) {
  const idWanted = Number($('editor-new-beacon-id').value);
  const taken = new Set(list('beacons').map((b) => b?.id));
  const id = Number.isInteger(idWanted) && !taken.has(idWanted) && $('editor-new-beacon-id').value !== '' ? idWanted : nextBeaconId();
  const num = (inputId, fallback) => { const v = Number($(inputId).value); return isNum(v) && $(inputId).value !== '' ? v : fallback; };
  const b = {
    id, position: [snap(x), snap(y)], facing_deg: headingDeg(num('editor-new-beacon-facing', 0)),
    aperture_deg: num('editor-new-beacon-aperture', 360), range_m: num('editor-new-beacon-range', 2),
  };
  ensureList('beacons').push(b);
  $('editor-new-beacon-id').value = '';
  return ensureList('beacons').length - 1;
}
function finishDraft() {
  const d = ed.draft;
  if (!d) return;
  // A double click's two clicks each added a point: drop points on top of the one before.
  const pts = [];
  for (const p of d.points) {
    const last = pts[pts.length - 1];
    if (!last || Math.hypot(p[0] - last[0], p[1] - last[1]) * layout().s > 4) pts.push(p);
  }
  const need = d.type === 'obstacle' ? 3 : 2;
  if (pts.length < need) {
    status(`${d.type === 'obstacle' ? 'An obstacle' : 'A track'} needs at least ${need} points: keep clicking (Esc cancels).`, true);
    ed.draft.points = pts;
    requestDraw();
    return;
  }
  checkpoint();
  if (d.type === 'obstacle') {
    ensureList('obstacles').push({ name: uniqueName('obstacles', 'obstacle'), polygon: pts });
    ed.sel = { type: 'obstacle', index: ed.doc.obstacles.length - 1 };
  } else {
    const width = Number($('editor-new-track-width').value);
    const t = { name: uniqueName('tracks', 'track'), points: pts, width_m: isNum(width) && width > 0 ? width : 0.02,
      closed: $('editor-new-track-closed').checked };
    ensureList('tracks').push(t);
    ed.sel = { type: 'track', index: ed.doc.tracks.length - 1 };
  }
  ed.draft = null;
  setTool('select');
  status(`Added ${ed.sel.type} ${ed.sel.index + 1} (${pts.length} points).`);
  changed(true);
}
function deleteSelection() {
  const s = ed.sel;
  if (!s) return;
  checkpoint();
  if (s.type === 'robot') {
    removeRobot(s.index, s.id);
    status(`Deleted robot ${s.id}.`);
  } else {
    const key = `${s.type}s`, item = list(key)[s.index];
    const pts = s.type === 'obstacle' ? item?.polygon : item?.points;
    const min = s.type === 'obstacle' ? 3 : 2;
    if (s.vertex !== undefined && Array.isArray(pts) && pts.length > min) {
      pts.splice(s.vertex, 1);
      ed.sel = { type: s.type, index: s.index };
      status(`Deleted point ${s.vertex + 1} of ${s.type} ${s.index + 1}.`);
      changed(true);
      return;
    }
    list(key).splice(s.index, 1);
    if (!list(key).length) delete ed.doc[key];
    status(`Deleted ${s.type} ${s.type === 'beacon' ? item?.id : s.index + 1}.`);
  }
  ed.sel = null;
  changed(true);
}
// The selection's rotation: robots and beacons turn in place, polygons and tracks about
// their centroid. `from` is the item as it was when the rotation began.
function rotateSelection(from, byDeg) {
  const s = ed.sel;
  if (s.type === 'robot') {
    const e = ed.doc.robots[s.index];
    if (isPose(e.pose)) setPose(e, [e.pose[0], e.pose[1], from + byDeg]);
  } else if (s.type === 'beacon') {
    ed.doc.beacons[s.index].facing_deg = headingDeg(from + byDeg);
  } else {
    const item = list(`${s.type}s`)[s.index];
    const key = s.type === 'obstacle' ? 'polygon' : 'points';
    const [cx, cy] = centroid(from);
    const c = Math.cos(degToRad(byDeg)), sn = Math.sin(degToRad(byDeg));
    item[key] = from.map(([x, y]) => [round3(cx + c * (x - cx) - sn * (y - cy)), round3(cy + sn * (x - cx) + c * (y - cy))]);
  }
}
function rotationOf(s) {
  if (s.type === 'robot') return ed.doc.robots[s.index].pose[2];
  if (s.type === 'beacon') return isNum(ed.doc.beacons[s.index].facing_deg) ? ed.doc.beacons[s.index].facing_deg : 0;
  return clone(s.type === 'obstacle' ? obstaclePoints(ed.doc.obstacles[s.index]) : trackPoints(ed.doc.tracks[s.index]));
}

// ------------------------------------------------------------------ from the run
function runOf() {
  const run = window.rilbed?.run;
  if (!run?.world) { status('No run is connected (no /rilbed/world yet): nothing to start from.', true); return null; }
  return run;
}
function startFromRun() {
  const run = runOf();
  if (!run) return;
  const W = run.world;
  const pts = (ps) => ps.map((p) => [round3(p.x_m), round3(p.y_m)]);
  const doc = {
    name: `${W.scenario || 'run'}_edited`,
    description: `Edited from the run of ${W.scenario || 'a scenario'} at t = ${(run.poses?.t_s ?? W.t_s ?? 0).toFixed(1)} s.`,
  };
  if (run.status?.mode === 'central' || run.status?.mode === 'distributed') doc.mode = run.status.mode;
  doc.field = { width_m: W.width_m, height_m: W.height_m, walls: W.walls !== false };
  doc.duration_s = 120;
  if (W.obstacles?.length) doc.obstacles = W.obstacles.map((o, i) => ({ name: `obstacle${i + 1}`, polygon: pts(o) }));
  if (W.tracks?.length) {
    doc.tracks = W.tracks.map((t, i) => {
      let p = pts(t.points);
      const closed = p.length > 3 && p[0][0] === p[p.length - 1][0] && p[0][1] === p[p.length - 1][1];
      if (closed) p = p.slice(0, -1);
      return { name: `track${i + 1}`, points: p, width_m: t.width_m, closed };
    });
  }
  if (W.beacons?.length) doc.beacons = W.beacons.map((b, i) => ({ id: i + 1, position: [round3(b.x_m), round3(b.y_m)] }));
  const poses = new Map((run.poses?.robots || []).map((r) => [r.id, r]));
  let bodies = 0;
  doc.robots = (W.robots || []).map((r) => {
    const e = { id: r.id };
    if (r.real) { e.kind = 'real'; e.link = { emulate: true }; }
    const p = poses.get(r.id);
    e.pose = p ? [round3(p.x_m), round3(p.y_m), headingDeg(radToDeg(p.theta_rad))] : 'random';
    e.controller = DEFAULT_CONTROLLER;
    if (bodyOverride(e, r.body)) ++bodies;
    return e;
  });
  if (doc.robots.some((r) => r.kind === 'real')) doc.camera = { emulate: true };
  const placed = doc.robots.filter((r) => isPose(r.pose));
  const nudged = nudgeApart(placed.map((r) => r.pose), placed.map(entryRadius), doc.field.walls, W.width_m, W.height_m,
    (doc.obstacles || []).map((o) => o.polygon));
  setDoc(doc, '', `Started from the run of ${W.scenario}: ${doc.robots.length} robots at their poses of t = ` +
    `${(run.poses?.t_s ?? 0).toFixed(1)} s${nudged ? ` (${nudged} moved apart by a millimetre or two: they touched)` : ''}. The run does not say its robots' controllers and sensors, its beacons' ` +
    'IDs, apertures and ranges, nor real robots\' links: they are defaults here (convoy; 360°, 2 m; emulated). ' +
    `${bodies ? `Nor their model files: the ${bodies} robots that are not Kheperas have their bodies and wheels as body: and wheels:. ` : ''}` +
    'To keep a file\'s, load it and use "Poses from run".');
}
// Entry e's `body:` and `wheels:` for a run's robot of body `b` (/rilbed/world's), unless it
// is a Khepera's (what an entry without them is). Returns whether it added them.
const round6 = (v) => Math.round(v * 1e6) / 1e6;
function bodyOverride(e, b) {
  if (!b) return false;
  const body = robotBody(b), K = KHEPERA_BODY;
  const same = (x, y) => Math.abs(x - y) < 1e-9;
  if (!body.outline.length && same(body.radius_m, K.radius_m) && same(body.wheel_base_m, K.wheel_base_m) &&
    same(body.wheel_radius_m, K.wheel_radius_m)) return false;
  e.body = body.outline.length ? { outline_m: body.outline.map((p) => p.map(round6)) } : { radius_m: round6(body.radius_m) };
  e.wheels = { base_m: round6(body.wheel_base_m), radius_m: round6(body.wheel_radius_m) };
  return true;
}
// The run's poses as start poses: robots that touch (a wall, an obstacle, each other) in
// the run would overlap by a rounding's fraction of a millimetre, which rilbed run refuses:
// such robots are moved apart by a millimetre or two. `radii`: each robot's bounding
// disc's. Returns how many moved.
function nudgeApart(poses, radii, walls, W, H, obstacles) {
  const gap = 0.001;
  const start = poses.map((p) => [p[0], p[1]]);
  for (let pass = 0; pass < 30; ++pass) {
    let moved = false;
    for (const [i, p] of poses.entries()) {
      const R = radii[i];
      if (walls) {
        const x = Math.min(Math.max(p[0], R + gap), W - R - gap), y = Math.min(Math.max(p[1], R + gap), H - R - gap);
        if (x !== p[0] || y !== p[1]) { p[0] = x; p[1] = y; moved = true; }
      }
      for (const pts of obstacles) {
        for (let k = 0; k < pts.length; ++k) {
          const a = pts[k], b = pts[(k + 1) % pts.length];
          const d = distToSegment(p, a, b);
          if (d >= R + gap / 2 || pointInPolygon(p, pts)) continue;
          const dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy || 1;
          const t = Math.max(0, Math.min(1, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2));
          const nx = p[0] - a[0] - t * dx, ny = p[1] - a[1] - t * dy, n = Math.hypot(nx, ny) || 1;
          p[0] += (nx / n) * (R + gap - d); p[1] += (ny / n) * (R + gap - d);
          moved = true;
        }
      }
    }
    for (let i = 0; i < poses.length; ++i) {
      for (let j = i + 1; j < poses.length; ++j) {
        const a = poses[i], b = poses[j], R2 = radii[i] + radii[j];
        const d = Math.hypot(b[0] - a[0], b[1] - a[1]);
        if (d >= R2 + gap / 2) continue;
        const ux = d > 1e-9 ? (b[0] - a[0]) / d : 1, uy = d > 1e-9 ? (b[1] - a[1]) / d : 0, push = (R2 + gap - d) / 2;
        a[0] -= ux * push; a[1] -= uy * push; b[0] += ux * push; b[1] += uy * push;
        moved = true;
      }
    }
    for (const p of poses) { p[0] = round3(p[0]); p[1] = round3(p[1]); }
    if (!moved) break;
  }
  return poses.filter((p, i) => p[0] !== round3(start[i][0]) || p[1] !== round3(start[i][1])).length;
}
function posesFromRun() {
  const run = runOf();
  if (!run) return;
  if (!run.poses) { status('The run has sent no poses yet.', true); return; }
  checkpoint();
  const F = field();
  const ids = new Set(robotItems().map((r) => r.id));
  const taken = run.poses.robots.filter((p) => ids.has(p.id));
  const poses = taken.map((p) => [round3(p.x_m), round3(p.y_m), headingDeg(radToDeg(p.theta_rad))]);
  // (Robots of the scenario the run does not have keep their places, and are kept clear of.)
  const others = robotItems().filter((r) => r.placed && !taken.some((p) => p.id === r.id));
  const radii = [...taken.map((p) => entryRadius(robotItems().find((x) => x.id === p.id).e)), ...others.map((r) => entryRadius(r.e))];
  const nudged = nudgeApart([...poses, ...others.map((r) => [r.x, r.y, r.th])], radii, F.walls, F.w, F.h, list('obstacles').map(obstaclePoints));
  taken.forEach((p, k) => {
    const r = robotItems().find((x) => x.id === p.id);
    placeRobot(r.index, r.id, ...poses[k]);
  });
  ed.sel = null;
  changed(true);
  status(`Took the poses of ${taken.length} robots from the run at t = ${run.poses.t_s.toFixed(1)} s` +
    `${nudged ? ` (${nudged} moved apart by a millimetre or two: they touched)` : ''}.`);
}

// ------------------------------------------------------------------ load and save
function loadText(text, name) {
  let read;
  try {
    read = readScenarioText(text);
  } catch (e) {
    status(`${name}: ${e.message}`, true);
    return;
  }
  setDoc(read.doc, read.header, ''); // (the file's leading comment lines are kept on save)
  status(`Loaded ${name}: ${robotItems().length} robots, ${list('obstacles').length} obstacles, ` +
    `${list('tracks').length} tracks, ${list('beacons').length} beacons.`);
  ed.loadedName = name;
  ed.loads = (ed.loads || 0) + 1;
}
function save() {
  if (ed.draft) finishDraft();
  const text = scenarioText();
  $('editor-yaml').value = text;
  const a = $('editor-download');
  if (a.href) URL.revokeObjectURL(a.href);
  a.href = URL.createObjectURL(new Blob([text], { type: 'text/yaml' }));
  a.download = 'scenario.yaml';
  a.click();
  const problems = findProblems();
  status(problems.length ? `Saved scenario.yaml, with ${problems.length} problem(s) listed below that rilbed run may refuse.`
    : 'Saved scenario.yaml.', problems.length > 0);
  ed.saves = (ed.saves || 0) + 1;
}
function newScenario() {
  setDoc({ name: 'new_scenario', field: { ...DEFAULT_FIELD }, duration_s: 60, robots: [] }, '',
    'A new, empty scenario: add robots (rilbed run needs at least one).');
}

// ------------------------------------------------------------------ problems
// What rilbed run would refuse, as far as the editor can tell (the run has the last word).
function findProblems() {
  const out = scenarioProblems(ed.doc, controllers.registry);
  if (controllers.error) out.unshift('controllers, their parameters and sensors are not checked: the list of controllers did not load.');
  return out;
}
function showProblems() {
  const ul = $('editor-problems');
  ul.replaceChildren(...findProblems().map((p) => { const li = document.createElement('li'); li.textContent = p; return li; }));
}

// ------------------------------------------------------------------ geometry
const layout = () => editorLayout(canvas.clientWidth, canvas.clientHeight, field(), { margin: MARGIN_PX, trayHeight: TRAY_HEIGHT_PX });
function trayPosition(L, k) { return [MARGIN_PX + 100 + k * 30, L.trayTop + TRAY_HEIGHT_PX / 2]; }
function trayRobots() { return robotItems().filter((r) => !r.placed); }
// Where the selection's rotation handle is on the canvas, or null.
function rotateHandle(L, s = ed.sel) {
  if (!s) return null;
  if (s.type === 'robot') {
    const e = ed.doc.robots[s.index];
    if (!e || !isPose(e.pose) || entryIds(e).length !== 1) return null;
    const [u, v] = toPx(L, e.pose[0], e.pose[1]);
    const d = Math.max(6, entryRadius(e) * L.s) + 16, a = degToRad(e.pose[2]);
    return [u + d * Math.cos(a), v - d * Math.sin(a)];
  }
  if (s.type === 'beacon') {
    const b = ed.doc.beacons[s.index];
    if (!b || !isPoint(b.position)) return null;
    const [u, v] = toPx(L, ...b.position), a = degToRad(isNum(b.facing_deg) ? b.facing_deg : 0);
    return [u + 24 * Math.cos(a), v - 24 * Math.sin(a)];
  }
  const pts = s.type === 'obstacle' ? obstaclePoints(ed.doc.obstacles[s.index]) : trackPoints(ed.doc.tracks[s.index]);
  if (!pts.length) return null;
  const px = pts.map((p) => toPx(L, ...p));
  const [cu] = toPx(L, ...centroid(pts));
  return [cu, Math.min(...px.map((p) => p[1])) - 24];
}
function selectedPoints(s = ed.sel) {
  if (!s || (s.type !== 'obstacle' && s.type !== 'track')) return null;
  const item = list(`${s.type}s`)[s.index];
  return s.type === 'obstacle' ? obstaclePoints(item) : trackPoints(item);
}

// What is under canvas point (u, v): the selection's handles first, then the items from
// the top of the drawing down.
function hitTest(u, v) {
  const L = layout();
  const near = (p, r) => p && Math.hypot(p[0] - u, p[1] - v) <= r;
  if (ed.sel) {
    if (near(rotateHandle(L), HANDLE_PX + 2)) return { ...ed.sel, handle: 'rotate' };
    const pts = selectedPoints();
    if (pts) {
      const i = pts.findIndex((p) => near(toPx(L, ...p), HANDLE_PX + 1));
      if (i >= 0) return { type: ed.sel.type, index: ed.sel.index, vertex: i, handle: 'vertex' };
    }
  }
  const tray = trayRobots();
  for (let k = 0; k < tray.length; ++k) {
    if (near(trayPosition(L, k), 12)) return { type: 'robot', index: tray[k].index, id: tray[k].id, tray: true };
  }
  let best = null;
  for (const r of robotItems().filter((x) => x.placed)) {
    const [ru, rv] = toPx(L, r.x, r.y), d = Math.hypot(ru - u, rv - v);
    if (d <= Math.max(8, entryRadius(r.e) * L.s) && (!best || d < best.d)) best = { d, r };
  }
  if (best) return { type: 'robot', index: best.r.index, id: best.r.id };
  const beacons = list('beacons');
  for (let i = beacons.length - 1; i >= 0; --i) {
    if (isPoint(beacons[i].position) && near(toPx(L, ...beacons[i].position), 10)) return { type: 'beacon', index: i };
  }
  const f = toField(L, u, v);
  const obstacles = list('obstacles');
  for (let i = obstacles.length - 1; i >= 0; --i) {
    const pts = obstaclePoints(obstacles[i]);
    if (pts.length >= 3 && (pointInPolygon(f, pts) || pts.some((p, k) => distToSegment(f, p, pts[(k + 1) % pts.length]) * L.s <= 5))) {
      return { type: 'obstacle', index: i };
    }
  }
  const tracks = list('tracks');
  for (let i = tracks.length - 1; i >= 0; --i) {
    const t = tracks[i], pts = trackPoints(t);
    const reach = Math.max(6, ((isNum(t.width_m) ? t.width_m : 0.02) * L.s) / 2 + 2);
    const n = t.closed ? pts.length : pts.length - 1;
    for (let k = 0; k < n; ++k) if (distToSegment(f, pts[k], pts[(k + 1) % pts.length]) * L.s <= reach) return { type: 'track', index: i };
  }
  return null;
}

// ------------------------------------------------------------------ drawing
let drawPending = false;
function requestDraw() {
  if (drawPending) return;
  drawPending = true;
  requestAnimationFrame(() => { drawPending = false; draw(); });
}
function draw() {
  if (!ed.doc || !canvas.clientWidth) return;
  const [, w] = prepareCanvas(canvas);
  const L = layout(), F = field();
  const P = (x, y) => toPx(L, x, y);
  const path = (pts, close) => {
    ctx.beginPath();
    pts.forEach((p, i) => { const [u, v] = P(p[0], p[1]); if (i) ctx.lineTo(u, v); else ctx.moveTo(u, v); });
    if (close) ctx.closePath();
  };
  const selected = (type, index) => ed.sel && ed.sel.type === type && ed.sel.index === index;
  // The field and a 10 cm grid.
  const [x0, y0] = P(0, F.h);
  ctx.fillStyle = '#fff'; ctx.fillRect(x0, y0, F.w * L.s, F.h * L.s);
  ctx.strokeStyle = '#eef0f3'; ctx.lineWidth = 1;
  ctx.beginPath();
  for (let x = 0.1; x < F.w - 1e-9; x += 0.1) { const [u] = P(x, 0); ctx.moveTo(u, y0); ctx.lineTo(u, y0 + F.h * L.s); }
  for (let y = 0.1; y < F.h - 1e-9; y += 0.1) { const [, v] = P(0, y); ctx.moveTo(x0, v); ctx.lineTo(x0 + F.w * L.s, v); }
  ctx.stroke();
  ctx.strokeStyle = F.walls ? '#1a9e2a' : '#8aa';
  ctx.lineWidth = F.walls ? 2.5 : 1;
  ctx.setLineDash(F.walls ? [] : [6, 4]);
  ctx.strokeRect(x0, y0, F.w * L.s, F.h * L.s);
  ctx.setLineDash([]);
  ctx.fillStyle = '#888'; ctx.font = '10px system-ui';
  ctx.fillText(`${F.w} × ${F.h} m`, x0 + F.w * L.s - 60, y0 - 6);
  // Tracks.
  list('tracks').forEach((t, i) => {
    const pts = trackPoints(t);
    if (pts.length < 1) return;
    ctx.strokeStyle = selected('track', i) ? 'rgba(36,86,199,0.55)' : 'rgba(40,40,40,0.4)';
    ctx.lineWidth = Math.max(2, (isNum(t.width_m) ? t.width_m : 0.02) * L.s);
    ctx.lineJoin = 'round'; ctx.lineCap = 'round';
    path(pts, t.closed === true); ctx.stroke();
  });
  // Moving obstacles: shown, not edited.
  ctx.setLineDash([4, 3]); ctx.strokeStyle = '#999'; ctx.lineWidth = 1;
  for (const m of list('moving_obstacles')) {
    if (!isPoint(m?.position)) continue;
    const [u, v] = P(...m.position);
    if (m.shape === 'polygon' && Array.isArray(m.vertices)) {
      path(m.vertices.filter(isPoint).map(([x, y]) => [x + m.position[0], y + m.position[1]]), true); ctx.stroke();
    } else {
      ctx.beginPath(); ctx.arc(u, v, Math.max(3, (isNum(m.radius_m) ? m.radius_m : 0.05) * L.s), 0, 2 * Math.PI); ctx.stroke();
    }
    if (isPoint(m.velocity_mps)) { ctx.beginPath(); ctx.moveTo(u, v); ctx.lineTo(u + 200 * m.velocity_mps[0], v - 200 * m.velocity_mps[1]); ctx.stroke(); }
  }
  ctx.setLineDash([]);
  // Obstacles.
  list('obstacles').forEach((o, i) => {
    const pts = obstaclePoints(o);
    if (!pts.length) return;
    ctx.fillStyle = 'rgba(90,90,90,0.45)';
    ctx.strokeStyle = selected('obstacle', i) ? '#2456c7' : '#555';
    ctx.lineWidth = selected('obstacle', i) ? 2.5 : 1.5;
    path(pts, true); ctx.fill(); ctx.stroke();
  });
  // Beacons: the aperture out to its range, faint; a stronger short wedge.
  list('beacons').forEach((b, i) => {
    if (!isPoint(b?.position)) return;
    const [u, v] = P(...b.position);
    const facing = degToRad(isNum(b.facing_deg) ? b.facing_deg : 0);
    const ap = degToRad(isNum(b.aperture_deg) ? Math.min(360, b.aperture_deg) : 360);
    const wedge = (r) => {
      ctx.beginPath();
      if (ap >= 2 * Math.PI - 1e-9) { ctx.arc(u, v, r, 0, 2 * Math.PI); return; }
      ctx.moveTo(u, v); ctx.arc(u, v, r, -(facing - ap / 2), -(facing + ap / 2), true); ctx.closePath();
    };
    ctx.save();
    if (F.walls) { ctx.beginPath(); ctx.rect(x0, y0, F.w * L.s, F.h * L.s); ctx.clip(); } // the walls stop its light
    ctx.fillStyle = 'rgba(224,168,0,0.07)'; wedge((isNum(b.range_m) ? b.range_m : 2) * L.s); ctx.fill();
    ctx.restore();
    ctx.fillStyle = 'rgba(224,168,0,0.35)'; wedge(22); ctx.fill();
    ctx.fillStyle = selected('beacon', i) ? '#2456c7' : '#e0a800';
    ctx.beginPath(); ctx.arc(u, v, 6, 0, 2 * Math.PI); ctx.fill();
    ctx.fillStyle = '#000'; ctx.font = '11px system-ui'; ctx.fillText(`B${b.id}`, u + 8, v - 8);
  });
  // Robots on the field.
  for (const r of robotItems().filter((x) => x.placed)) drawRobot(r, robotShape(L, r.e, r.x, r.y, r.th), selected('robot', r.index));
  // The tray: robots with random poses.
  ctx.fillStyle = '#f1f3f6'; ctx.fillRect(0, L.trayTop, w, TRAY_HEIGHT_PX);
  ctx.fillStyle = '#6b7684'; ctx.font = '11px system-ui';
  ctx.fillText('random pose:', MARGIN_PX, L.trayTop + TRAY_HEIGHT_PX / 2 + 4);
  const tray = trayRobots();
  tray.forEach((r, k) => {
    const [u, v] = trayPosition(L, k);
    drawRobot(r, { u, v, radius: 10, outline: null, heading: null }, ed.sel?.type === 'robot' && ed.sel.index === r.index && ed.sel.id === r.id, true);
  });
  if (!tray.length) ctx.fillText('(none: every robot has a pose; drag one here to make its pose random)', MARGIN_PX + 100, L.trayTop + TRAY_HEIGHT_PX / 2 + 4);
  // The selection's handles.
  if (ed.sel) {
    const pts = selectedPoints();
    if (pts) {
      pts.forEach((p, k) => {
        const [u, v] = P(...p);
        ctx.fillStyle = ed.sel.vertex === k ? '#2456c7' : '#fff'; ctx.strokeStyle = '#2456c7'; ctx.lineWidth = 1.5;
        ctx.fillRect(u - HANDLE_PX / 2 - 1, v - HANDLE_PX / 2 - 1, HANDLE_PX + 2, HANDLE_PX + 2);
        ctx.strokeRect(u - HANDLE_PX / 2 - 1, v - HANDLE_PX / 2 - 1, HANDLE_PX + 2, HANDLE_PX + 2);
      });
    }
    const hnd = rotateHandle(L);
    if (hnd) {
      const c = ed.sel.type === 'robot' ? P(...ed.doc.robots[ed.sel.index].pose.slice(0, 2))
        : ed.sel.type === 'beacon' ? P(...ed.doc.beacons[ed.sel.index].position) : [hnd[0], hnd[1] + 24];
      ctx.strokeStyle = '#2456c7'; ctx.lineWidth = 1; ctx.setLineDash([3, 2]);
      ctx.beginPath(); ctx.moveTo(...c); ctx.lineTo(...hnd); ctx.stroke(); ctx.setLineDash([]);
      ctx.fillStyle = '#fff'; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.arc(hnd[0], hnd[1], HANDLE_PX, 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
      ctx.beginPath(); ctx.arc(hnd[0], hnd[1], 3.5, 0.3, 5.2); ctx.stroke(); // a "turn" mark
    }
  }
  // The shape being drawn.
  if (ed.draft) {
    const pts = ed.draft.points.slice();
    if (ed.mouse) pts.push(toField(L, ...ed.mouse).map(snap));
    ctx.strokeStyle = '#2456c7'; ctx.lineWidth = 1.5; ctx.setLineDash([5, 3]);
    path(pts, ed.draft.type === 'obstacle' && pts.length > 2); ctx.stroke(); ctx.setLineDash([]);
    ctx.fillStyle = '#2456c7';
    for (const p of ed.draft.points) { const [u, v] = P(...p); ctx.fillRect(u - 3, v - 3, 6, 6); }
  }
  // A tray robot being dragged onto the field.
  if (ed.drag?.mode === 'place' && ed.mouse) {
    ctx.globalAlpha = 0.6;
    drawRobot(ed.drag.robot, robotShape(L, ed.drag.robot.e, ...toField(L, ...ed.mouse), 90), true);
    ctx.globalAlpha = 1;
  }
}
// How a robot of entry e at (x, y) metres, heading th degrees, is drawn on layout L:
// {u, v, radius (px, its bounding disc), outline (canvas points, or null: a disc or a
// square), heading (the mark's end)}. Its body override's shape (body.js), else a Khepera's disc.
function robotShape(L, e, x, y, th) {
  const [u, v] = toPx(L, x, y), a = degToRad(th);
  const body = entryBody(e);
  const d = body && bodyOnCanvas(body, { x_m: x, y_m: y, theta_rad: a }, (fx, fy) => toPx(L, fx, fy), L.s, { minRadiusPx: 5 });
  const radius = d ? d.radius_px : Math.max(5, ROBOT_RADIUS_M * L.s);
  const outline = d?.outline ?? null;
  return { u, v, radius, outline, heading: outline ? d.heading : [u + radius * 1.2 * Math.cos(a), v - radius * 1.2 * Math.sin(a)] };
}
// A robot drawn as `shape` (robotShape's; in the tray a 10 px one without a heading): its
// outline, else a disc (virtual) or a square (real), its heading mark, its label.
function drawRobot(r, shape, isSelected, inTray = false) {
  const real = r.e?.kind === 'real';
  const { u, v, radius, outline, heading } = shape;
  ctx.lineWidth = 2;
  ctx.strokeStyle = isSelected ? '#2456c7' : real ? '#1d6fb8' : '#d22828';
  ctx.fillStyle = isSelected ? 'rgba(36,86,199,0.15)' : 'rgba(255,255,255,0.8)';
  if (outline) {
    ctx.beginPath();
    outline.forEach(([x, y], i) => { if (i) ctx.lineTo(x, y); else ctx.moveTo(x, y); });
    ctx.closePath(); ctx.fill(); ctx.stroke();
  } else if (real) {
    ctx.fillRect(u - radius, v - radius, 2 * radius, 2 * radius);
    ctx.strokeRect(u - radius, v - radius, 2 * radius, 2 * radius);
  } else {
    ctx.beginPath(); ctx.arc(u, v, radius, 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
  }
  if (heading) { ctx.beginPath(); ctx.moveTo(u, v); ctx.lineTo(heading[0], heading[1]); ctx.stroke(); }
  ctx.fillStyle = '#111'; ctx.font = '11px system-ui';
  if (inTray) { ctx.textAlign = 'center'; ctx.fillText(String(r.id), u, v + 4); ctx.textAlign = 'start'; }
  else ctx.fillText(`${r.id}${controllerTag(r.e)}${modelTag(r.e)}`, u + radius + 3, v - radius - 1);
}
// What a robot's label says of its model: the model file's name, in brackets; nothing
// without one.
function modelTag(e) {
  const m = modelName(e);
  return m ? ` [${m}]` : '';
}
// What a robot's label says after its ID: its controller's name, unless it runs the default.
function controllerTag(e) {
  const ref = controllerRef(e);
  if (!ref?.name) return ' ?';
  return ref.library || ref.name !== DEFAULT_CONTROLLER ? ` ${ref.name}` : '';
}

// ------------------------------------------------------------------ pointer and keys
function canvasPoint(e) {
  const r = canvas.getBoundingClientRect();
  return [e.clientX - r.left, e.clientY - r.top];
}
canvas.addEventListener('pointerdown', (e) => {
  if (e.button !== 0 || !ed.doc) return;
  canvas.focus();
  canvas.setPointerCapture(e.pointerId);
  const [u, v] = canvasPoint(e);
  const L = layout();
  const [x, y] = toField(L, u, v);
  ed.mouse = [u, v];
  if (ed.tool === 'obstacle' || ed.tool === 'track') {
    if (!ed.draft || ed.draft.type !== ed.tool) ed.draft = { type: ed.tool, points: [] };
    ed.draft.points.push([snap(x), snap(y)]);
    requestDraw();
    return;
  }
  if (ed.tool === 'robot' || ed.tool === 'beacon') {
    if (v >= L.trayTop) return;
    checkpoint();
    const index = ed.tool === 'robot' ? newRobot(snap(x), snap(y)) : newBeacon(x, y);
    ed.sel = ed.tool === 'robot' ? { type: 'robot', index, id: ed.doc.robots[index].id } : { type: 'beacon', index };
    // Dragging on while the button is down aims it.
    ed.drag = { mode: 'aim', start: [u, v], moved: false };
    status(`Added ${ed.sel.type} ${ed.sel.type === 'robot' ? ed.sel.id : ed.doc.beacons[index].id}; drag to aim it.`);
    changed(true);
    return;
  }
  const hit = hitTest(u, v);
  if (!hit) {
    ed.sel = null;
    changed(true);
    return;
  }
  const { handle, ...sel } = hit;
  ed.sel = sel;
  const before = JSON.stringify(ed.doc);
  if (handle === 'rotate') {
    ed.drag = { mode: 'rotate', before, from: rotationOf(sel), a0: handleAngle(L, u, v, sel) };
  } else if (handle === 'vertex') {
    ed.drag = { mode: 'vertex', before, start: [x, y], from: clone(selectedPoints()[hit.vertex]) };
  } else if (sel.tray) {
    ed.drag = { mode: 'place', before, robot: trayRobots().find((r) => r.index === sel.index && r.id === sel.id) };
  } else {
    ed.drag = { mode: 'move', before, start: [x, y], from: clone(positionOf(sel)) };
  }
  changed(true);
});
canvas.addEventListener('pointermove', (e) => {
  const [u, v] = canvasPoint(e);
  ed.mouse = [u, v];
  const d = ed.drag;
  if (!d) {
    const hit = ed.tool === 'select' ? hitTest(u, v) : null;
    canvas.style.cursor = ed.tool !== 'select' ? 'crosshair' : !hit ? 'default' : hit.handle === 'rotate' ? 'alias' : 'move';
    if (ed.draft) requestDraw();
    return;
  }
  const L = layout();
  const [x, y] = toField(L, u, v);
  if (d.mode === 'aim') {
    if (Math.hypot(u - d.start[0], v - d.start[1]) < 6 && !d.moved) return;
    d.moved = true;
    const a = headingDeg(radToDeg(Math.atan2(-(v - d.start[1]), u - d.start[0])));
    if (ed.sel.type === 'robot') { const p = ed.doc.robots[ed.sel.index].pose; setPose(ed.doc.robots[ed.sel.index], [p[0], p[1], a]); }
    else ed.doc.beacons[ed.sel.index].facing_deg = a;
  } else if (d.mode === 'rotate') {
    noteChange(d);
    // A robot or a beacon faces the pointer; a polygon or a track turns as far as the pointer has.
    const a = handleAngle(L, u, v, ed.sel);
    if (ed.sel.type === 'robot' || ed.sel.type === 'beacon') rotateSelection(0, snapOn() ? Math.round(a / 5) * 5 : a);
    else rotateSelection(d.from, a - d.a0);
  } else if (d.mode === 'vertex') {
    noteChange(d);
    const pts = ed.sel.type === 'obstacle' ? ed.doc.obstacles[ed.sel.index].polygon : ed.doc.tracks[ed.sel.index].points;
    pts[ed.sel.vertex] = [snap(x), snap(y)];
  } else if (d.mode === 'move') {
    noteChange(d);
    moveSelection(d.from, x - d.start[0], y - d.start[1]);
  }
  refreshForm();
  requestDraw();
});
canvas.addEventListener('pointerup', (e) => {
  const d = ed.drag;
  ed.drag = null;
  if (!d) return;
  const [u, v] = canvasPoint(e);
  const L = layout();
  if (d.mode === 'place') {
    const [x, y] = toField(L, u, v);
    if (v < L.trayTop && d.robot) {
      noteChange(d);
      const index = placeRobot(d.robot.index, d.robot.id, snap(x), snap(y), 90);
      ed.sel = { type: 'robot', index, id: d.robot.id };
      status(`Placed robot ${d.robot.id} at (${snap(x)}, ${snap(y)}).`);
    }
    changed(true);
    return;
  }
  if (d.mode === 'move' && ed.sel?.type === 'robot' && v >= L.trayTop && d.changed) {
    // Dropped in the tray: the robot's pose becomes random again.
    ed.doc.robots[ed.sel.index].pose = 'random';
    status(`Robot ${ed.sel.id} now starts at a random pose.`);
    ed.sel = { ...ed.sel, tray: true };
    changed(true);
    return;
  }
  if (d.changed || d.mode === 'aim') changed(true);
});
// The first change of a drag puts the document as it was before on the undo stack.
function noteChange(d) {
  if (d.changed) return;
  d.changed = true;
  ed.undo.push(d.before);
  if (ed.undo.length > UNDO_DEPTH) ed.undo.shift();
  ed.redo = [];
}
function handleAngle(L, u, v, s) {
  let c;
  if (s.type === 'robot') c = toPx(L, ...ed.doc.robots[s.index].pose.slice(0, 2));
  else if (s.type === 'beacon') c = toPx(L, ...ed.doc.beacons[s.index].position);
  else c = toPx(L, ...centroid(selectedPoints(s)));
  return radToDeg(Math.atan2(-(v - c[1]), u - c[0]));
}
function positionOf(s) {
  if (s.type === 'robot') return ed.doc.robots[s.index].pose;
  if (s.type === 'beacon') return ed.doc.beacons[s.index].position;
  return selectedPoints(s);
}
function moveSelection(from, dx, dy) {
  const s = ed.sel;
  if (snapOn()) { dx = Math.round(dx * 100) / 100; dy = Math.round(dy * 100) / 100; }
  if (s.type === 'robot') setPose(ed.doc.robots[s.index], [snap(from[0] + dx), snap(from[1] + dy), from[2]]);
  else if (s.type === 'beacon') ed.doc.beacons[s.index].position = [snap(from[0] + dx), snap(from[1] + dy)];
  else {
    const moved = from.map(([x, y]) => [round3(x + dx), round3(y + dy)]);
    if (s.type === 'obstacle') ed.doc.obstacles[s.index].polygon = moved; else ed.doc.tracks[s.index].points = moved;
  }
}
canvas.addEventListener('dblclick', (e) => {
  if (ed.draft) { e.preventDefault(); finishDraft(); }
});
// Shift + wheel turns the robot (or beacon, obstacle, track) under the pointer, 5° a notch.
canvas.addEventListener('wheel', (e) => {
  if (!e.shiftKey || !ed.doc) return;
  const [u, v] = canvasPoint(e);
  const hit = hitTest(u, v);
  const target = hit && !hit.tray && !hit.handle ? hit : hit?.handle ? { type: hit.type, index: hit.index, id: hit.id } : null;
  if (!target) return;
  e.preventDefault();
  const delta = e.deltaY || e.deltaX;
  if (!delta) return;
  checkpoint();
  ed.sel = target;
  rotateSelection(rotationOf(target), delta < 0 ? 5 : -5);
  changed(true);
}, { passive: false });
canvas.addEventListener('keydown', (e) => {
  const key = e.key;
  let handled = true;
  if (key === 'Enter') finishDraft();
  else if (key === 'Escape') { if (ed.draft) ed.draft = null; else ed.sel = null; setTool('select'); changed(true); }
  else if ((key === 'Delete' || key === 'Backspace') && ed.draft) { ed.draft.points.pop(); requestDraw(); }
  else if (key === 'Delete' || key === 'Backspace') deleteSelection();
  else if ((e.ctrlKey || e.metaKey) && key.toLowerCase() === 'z') undo(!e.shiftKey);
  else if ((e.ctrlKey || e.metaKey) && key.toLowerCase() === 'y') undo(false);
  else if (key.startsWith('Arrow') && ed.sel && !ed.sel.tray) {
    const step = e.shiftKey ? 0.01 : 0.001;
    const [dx, dy] = { ArrowLeft: [-step, 0], ArrowRight: [step, 0], ArrowUp: [0, step], ArrowDown: [0, -step] }[key];
    checkpoint();
    const from = clone(positionOf(ed.sel));
    if (ed.sel.vertex !== undefined) {
      const pts = ed.sel.type === 'obstacle' ? ed.doc.obstacles[ed.sel.index].polygon : ed.doc.tracks[ed.sel.index].points;
      pts[ed.sel.vertex] = [round3(pts[ed.sel.vertex][0] + dx), round3(pts[ed.sel.vertex][1] + dy)];
    } else if (ed.sel.type === 'robot' || ed.sel.type === 'beacon') {
      const p = positionOf(ed.sel);
      const moved = [round3(p[0] + dx), round3(p[1] + dy)];
      if (ed.sel.type === 'robot') setPose(ed.doc.robots[ed.sel.index], [...moved, p[2]]); else ed.doc.beacons[ed.sel.index].position = moved;
    } else moveSelection(from, dx, dy);
    changed();
  } else if (!e.ctrlKey && !e.metaKey && !e.altKey && { v: 1, r: 1, o: 1, t: 1, b: 1 }[key]) {
    setTool({ v: 'select', r: 'robot', o: 'obstacle', t: 'track', b: 'beacon' }[key]);
  } else handled = false;
  if (handled) { e.preventDefault(); e.stopPropagation(); } // not the page's manual driving
});

// ------------------------------------------------------------------ tools
function setTool(tool) {
  if (tool !== 'obstacle' && tool !== 'track') ed.draft = null;
  else if (ed.draft && ed.draft.type !== tool) ed.draft = null;
  ed.tool = tool;
  for (const r of document.querySelectorAll('input[name="editor-tool"]')) r.checked = r.value === tool;
  for (const span of document.querySelectorAll('#editor-tool-options [data-tool]')) span.hidden = !span.dataset.tool.split(' ').includes(tool);
  $('editor-hint').textContent = {
    select: 'Click to select, drag to move; drag the round handle to rotate (or shift + wheel); drag square handles to move a ' +
      'point; Delete removes the selection (or the chosen point); arrows nudge by 1 mm (shift: 1 cm); ctrl+z undoes. ' +
      'Drag a robot from the tray onto the field to give it a pose.',
    robot: 'Click on the field to place a robot; keep the button down and drag to aim it.',
    obstacle: 'Click the vertices; double-click or Enter closes the polygon; Backspace removes the last point; Esc cancels.',
    track: 'Click the points; double-click or Enter ends the track; Backspace removes the last point; Esc cancels.',
    beacon: 'Click on the field to place a beacon; keep the button down and drag to aim it.',
  }[tool];
  canvas.style.cursor = tool === 'select' ? 'default' : 'crosshair';
  requestDraw();
}
for (const r of document.querySelectorAll('input[name="editor-tool"]')) {
  r.addEventListener('change', () => { if (r.checked) { setTool(r.value); canvas.focus(); } });
}

// ------------------------------------------------------------------ the property form
// Each row: {label, get, set, type, options, step, ...}; a change is one undo step.
let formRows = [];
function numberField(label, get, set, step = 0.001, extra = {}) { return { label, get, set, type: 'number', step, ...extra }; }
// The robot's controller: one of the registry's, shown with its plug-in library's file name
// if it has one, its name as value (unique in a registry); or, when the registry has not the
// entry's own (flagged in the problems), that one too, kept as loaded. Its value is AS_LOADED,
// not its name: that may be a registry entry's of another library, or a built-in's. None to
// choose while the list has not loaded.
const AS_LOADED = '';
function controllerRow(e) {
  const registry = controllers.registry;
  const entries = registry?.entries ?? [];
  const current = () => registry?.match(controllerRef(e()))?.name ?? AS_LOADED;
  const options = entries.map((c) => c.name);
  const labels = Object.fromEntries(entries.map((c) => [c.name, controllerLabel(c)]));
  const titles = Object.fromEntries(entries.map((c) => [c.name, controllerTitle(c)]));
  if (current() === AS_LOADED) {
    options.push(AS_LOADED);
    [labels[AS_LOADED], titles[AS_LOADED]] = ownController(e(), registry);
  }
  return {
    label: 'controller', type: 'select', options, labels, titles, disabled: !registry, get: current,
    set: (v) => { const c = registry?.find(v); if (c) setController(e(), c); },
  };
}
// The label and title of a robot's controller the registry does not have, as loaded.
function ownController(e, registry) {
  const ref = controllerRef(e);
  const label = ref ? controllerLabel(ref) : JSON.stringify(e.controller);
  if (!registry) return [label, 'the list of controllers did not load'];
  return [label, `not a controller of the registry${ref?.library ? ` (${ref.name} of ${ref.library})` : ''}: kept as loaded`];
}
// One parameter of the robot's controller: a number input with its unit, its default as
// the placeholder and its range; emptied, the parameter is left out (its default applies).
function paramRow(e, p) {
  return numberField(p.name, () => e().params?.[p.name], (v) => setParam(e(), p.name, v), p.integer ? 1 : 'any', {
    name: `param_${p.name}`, unit: p.unit, title: paramDescription(p), emptyIsNull: true,
    min: p.min ?? undefined, max: p.max ?? undefined,
    placeholder: p.required ? 'required' : p.default !== null ? numberText(p.default) : '',
  });
}
function formFor(s) {
  const rows = [];
  if (!s) {
    return { title: 'Scenario', rows: [], note: 'Name, duration and field are in the bar above. Select an item to edit it.' };
  }
  if (s.type === 'robot') {
    const e = () => ed.doc.robots[s.index];
    const group = entryIds(e()).length > 1;
    if (group) {
      rows.push({ label: 'ids (the group)', type: 'text', get: () => String(e().ids), set: (v) => { if (parseIds(v)?.length) e().ids = v.trim(); } });
    } else {
      rows.push(numberField('id', () => entryIds(e())[0], (v) => {
        if (!Number.isInteger(v) || v < 1) return;
        ed.doc.robots[s.index] = renameKey(e(), e().id !== undefined ? 'id' : 'ids', 'id', v); s.id = v;
      }, 1, { min: 1 }));
    }
    rows.push({ label: 'kind', type: 'select', options: ['virtual', 'real'], get: () => (e().kind === 'real' ? 'real' : 'virtual'), set: (v) => setKind(s.index, v) });
    rows.push(controllerRow(e));
    if (isPose(e().pose) && !group) {
      rows.push(numberField('x_m', () => e().pose[0], (v) => setPose(e(), [v, e().pose[1], e().pose[2]])));
      rows.push(numberField('y_m', () => e().pose[1], (v) => setPose(e(), [e().pose[0], v, e().pose[2]])));
      rows.push(numberField('theta_deg', () => e().pose[2], (v) => setPose(e(), [e().pose[0], e().pose[1], v]), 1));
    }
    const entry = controllers.registry?.match(controllerRef(e()));
    if (entry?.params.length) rows.push({ type: 'heading', label: `parameters of ${entry.name}` }, ...entry.params.map((p) => paramRow(e, p)));
    const shown = ['id', 'ids', 'kind', 'controller', 'pose', ...(entry ? ['params'] : [])];
    const kept = Object.keys(e()).filter((k) => !shown.includes(k));
    return {
      title: `Robot ${s.id}${group ? ` (of group ${e().ids})` : ''}`, rows,
      note: `${isPose(e().pose) && !group ? '' : 'Random pose: drag it from the tray onto the field to place it' +
        `${group ? ' (it then leaves its group)' : ''}. `}${group ? 'kind, controller and parameters apply to the whole group. ' : ''}` +
        `${kept.length ? `Kept as loaded: ${kept.join(', ')}.` : ''}`,
      actions: isPose(e().pose) && !group ? [['random pose', () => { e().pose = 'random'; s.tray = true; }]] : [],
    };
  }
  if (s.type === 'beacon') {
    const b = () => ed.doc.beacons[s.index];
    rows.push(numberField('id', () => b().id, (v) => { if (Number.isInteger(v)) b().id = v; }, 1));
    rows.push(numberField('x_m', () => b().position[0], (v) => { b().position = [round3(v), b().position[1]]; }));
    rows.push(numberField('y_m', () => b().position[1], (v) => { b().position = [b().position[0], round3(v)]; }));
    rows.push(numberField('facing_deg', () => b().facing_deg ?? 0, (v) => { b().facing_deg = headingDeg(v); }, 1));
    rows.push(numberField('aperture_deg', () => b().aperture_deg ?? 360, (v) => { if (v > 0 && v <= 360) b().aperture_deg = v; }, 1, { min: 1, max: 360 }));
    rows.push(numberField('range_m', () => b().range_m ?? 2, (v) => { if (v > 0) b().range_m = v; }, 0.01, { min: 0.01 }));
    return { title: `Beacon ${b().id}`, rows };
  }
  const key = s.type === 'obstacle' ? 'polygon' : 'points';
  const item = () => list(`${s.type}s`)[s.index];
  rows.push({ label: 'name', type: 'text', get: () => item().name ?? '', set: (v) => { if (v) item().name = v; else delete item().name; } });
  if (s.type === 'track') {
    rows.push(numberField('width_m', () => item().width_m ?? 0.02, (v) => { if (v > 0) item().width_m = v; }, 0.001, { min: 0.001 }));
    rows.push({ label: 'closed', type: 'checkbox', get: () => item().closed === true, set: (v) => { item().closed = v; } });
  }
  (item()[key] || []).forEach((p, k) => {
    rows.push({ label: `point ${k + 1}`, type: 'pair',
      get: () => item()[key][k], set: (v) => { item()[key][k] = v; } });
  });
  return { title: `${s.type === 'obstacle' ? 'Obstacle' : 'Track'} ${s.index + 1}`, rows,
    note: 'Drag the square handles to move its points; select one and press Delete to remove it.' };
}
function renderForm() {
  const form = $('editor-form');
  form.replaceChildren();
  if (ed.sel && !selectionExists()) ed.sel = null;
  const spec = formFor(ed.sel);
  const h = document.createElement('h3');
  h.textContent = spec.title;
  form.append(h);
  formRows = [];
  for (const row of spec.rows) form.append(row.type === 'heading' ? formHeading(row.label) : formRow(row));
  for (const [text, act] of spec.actions || []) {
    const b = document.createElement('button');
    b.type = 'button'; b.textContent = text;
    b.addEventListener('click', () => { checkpoint(); act(); changed(true); });
    form.append(b);
  }
  if (spec.note) {
    const p = document.createElement('p');
    p.className = 'muted small';
    p.textContent = spec.note;
    form.append(p);
  }
  refreshForm();
  updateButtons();
}
function formHeading(text) {
  const h = document.createElement('h4');
  h.textContent = text;
  return h;
}
// A row of the form: its label, its input(s) and, for a number with a unit, the unit.
function formRow(row) {
  const label = document.createElement('label');
  label.className = 'editor-row';
  if (row.title) label.title = row.title;
  const span = document.createElement('span');
  span.textContent = row.label;
  label.append(span);
  const apply = (value) => { checkpoint(); row.set(value); changed(true); };
  const inputs = row.type === 'select' ? [selectInput(row, apply)] : row.type === 'checkbox' ? [checkboxInput(apply)]
    : row.type === 'pair' ? [0, 1].map((k) => pairInput(row, k, apply)) : [plainInput(row, apply)];
  inputs.forEach((i, k) => { i.name = row.name ?? `${row.label}${inputs.length > 1 ? ['_x', '_y'][k] : ''}`.replace(/\W+/g, '_'); });
  label.append(...inputs);
  if (row.unit !== undefined) {
    const unit = document.createElement('span');
    unit.className = 'editor-unit muted small';
    unit.textContent = row.unit || '(no unit)';
    label.append(unit);
  }
  formRows.push({ row, inputs });
  return label;
}
function selectInput(row, apply) {
  const sel = document.createElement('select');
  for (const o of row.options) {
    const option = new Option(row.labels?.[o] ?? o, o);
    if (row.titles?.[o]) option.title = row.titles[o];
    sel.append(option);
  }
  sel.disabled = !!row.disabled;
  sel.addEventListener('change', () => apply(sel.value));
  return sel;
}
function checkboxInput(apply) {
  const box = document.createElement('input');
  box.type = 'checkbox';
  box.addEventListener('change', () => apply(box.checked));
  return box;
}
function pairInput(row, k, apply) {
  const input = document.createElement('input');
  input.type = 'number'; input.step = '0.001';
  input.addEventListener('change', () => {
    const v = Number(input.value);
    if (input.value === '' || !isNum(v)) return;
    const p = [...row.get()];
    p[k] = round3(v);
    apply(p);
  });
  return input;
}
function plainInput(row, apply) {
  const input = document.createElement('input');
  input.type = row.type;
  if (row.step) input.step = String(row.step);
  if (row.min !== undefined) input.min = String(row.min);
  if (row.max !== undefined) input.max = String(row.max);
  if (row.placeholder) input.placeholder = row.placeholder;
  input.addEventListener('change', () => {
    if (row.type !== 'number') { apply(input.value); return; }
    const v = Number(input.value);
    if (input.value === '' && row.emptyIsNull && !input.validity.badInput) apply(null);
    else if (input.value === '' || !isNum(v)) refreshForm();
    else apply(v);
  });
  return input;
}
function refreshForm() {
  if (ed.sel && !selectionExists()) { renderForm(); return; }
  for (const { row, inputs } of formRows) {
    let v;
    try { v = row.get(); } catch { continue; }
    if (row.type === 'pair') inputs.forEach((i, k) => { if (document.activeElement !== i) i.value = v?.[k] ?? ''; });
    else if (row.type === 'checkbox') inputs[0].checked = !!v;
    else if (document.activeElement !== inputs[0]) inputs[0].value = v ?? '';
  }
}
function selectionExists() {
  const s = ed.sel;
  if (s.type === 'robot') return entryIds(ed.doc.robots?.[s.index]).includes(s.id);
  return !!list(`${s.type}s`)[s.index];
}
$('editor-form').addEventListener('submit', (e) => e.preventDefault());

// The scenario's own fields (the bar above the canvas).
const scenarioInputs = {
  'editor-name': { get: () => ed.doc.name ?? '', set: (v) => { if (v) ed.doc.name = v; else delete ed.doc.name; } },
  'editor-duration': { get: () => ed.doc.duration_s ?? '', set: (v) => { const n = Number(v); if (v === '') delete ed.doc.duration_s; else if (n > 0) ed.doc.duration_s = n; } },
  'editor-width': { get: () => ed.doc.field?.width_m ?? '', set: (v) => setField('width_m', v) },
  'editor-height': { get: () => ed.doc.field?.height_m ?? '', set: (v) => setField('height_m', v) },
  'editor-walls': { get: () => ed.doc.field?.walls !== false, set: (v) => { if (v && ed.doc.field) delete ed.doc.field.walls; else if (!v) { ed.doc.field = ed.doc.field || {}; ed.doc.field.walls = false; } } },
};
function setField(key, v) {
  const n = Number(v);
  if (v === '' || !(n > 0)) return;
  if (!ed.doc.field || typeof ed.doc.field !== 'object') ed.doc.field = {};
  ed.doc.field[key] = n;
}
function syncScenarioInputs() {
  $('editor-width').placeholder = String(DEFAULT_FIELD.width_m);
  $('editor-height').placeholder = String(DEFAULT_FIELD.height_m);
  for (const [id, io] of Object.entries(scenarioInputs)) {
    const input = $(id);
    if (input.type === 'checkbox') input.checked = io.get(); else input.value = io.get();
  }
}
for (const [id, io] of Object.entries(scenarioInputs)) {
  $(id).addEventListener('change', () => {
    checkpoint();
    io.set($(id).type === 'checkbox' ? $(id).checked : $(id).value.trim());
    syncScenarioInputs();
    changed();
  });
}

// ------------------------------------------------------------------ the panel's buttons
// ------------------------------------------------------------------ the controllers
async function loadControllers() {
  try {
    controllers.registry = await loadRegistry();
  } catch (e) {
    controllers.error = e.message;
  }
  controllers.loaded = true;
  showControllersState();
  fillNewRobotControllers();
  changed(true); // the form, its parameters and the problems, now with the registry
}
function showControllersState() {
  const p = $('editor-controllers');
  p.hidden = controllers.loaded && !controllers.error;
  p.classList.toggle('editor-bad', !!controllers.error);
  p.textContent = controllers.error
    ? `The list of controllers did not load (${controllers.error}): no controller can be chosen, and the robots' ` +
      'controllers, parameters and sensors are not checked. Reload the page to try again.'
    : 'Loading the list of controllers…';
}
function fillNewRobotControllers() {
  const select = $('editor-new-controller');
  const entries = controllers.registry?.entries ?? [];
  select.replaceChildren(...entries.map((c) => {
    const o = new Option(controllerLabel(c), c.name);
    o.title = controllerTitle(c);
    return o;
  }));
  if (entries.some((c) => c.name === DEFAULT_CONTROLLER)) select.value = DEFAULT_CONTROLLER;
  select.disabled = !entries.length;
}

$('editor-from-run').addEventListener('click', startFromRun);
$('editor-poses-from-run').addEventListener('click', posesFromRun);
$('editor-new').addEventListener('click', newScenario);
$('editor-save').addEventListener('click', save);
$('editor-delete').addEventListener('click', () => { deleteSelection(); canvas.focus(); });
$('editor-undo').addEventListener('click', () => undo(true));
$('editor-redo').addEventListener('click', () => undo(false));
$('editor-file').addEventListener('change', async () => {
  const file = $('editor-file').files[0];
  if (!file) return;
  loadText(await file.text(), file.name);
  $('editor-file').value = '';
});
const panel = $('editor-panel');
panel.open = localStorage.getItem('rilbed-editor-open') === '1';
panel.addEventListener('toggle', () => {
  localStorage.setItem('rilbed-editor-open', panel.open ? '1' : '0');
  if (panel.open) requestDraw();
});
new ResizeObserver(requestDraw).observe(canvas);

newScenario();
status('');
showControllersState();
fillNewRobotControllers();
loadControllers();

// For tests and the curious: the editor's document and its canvas geometry.
window.rilbedEditor = {
  get doc() { return ed.doc; },
  get yaml() { return ed.yaml; },
  get selection() { return ed.sel; },
  get tool() { return ed.tool; },
  get saves() { return ed.saves || 0; },
  get loadedName() { return ed.loadedName; },
  get loads() { return ed.loads || 0; },
  project: (x, y) => toPx(layout(), x, y),               // field metres -> canvas CSS pixels
  trayPosition: (id) => { const k = trayRobots().findIndex((r) => r.id === id); return k < 0 ? null : trayPosition(layout(), k); },
  rotateHandle: () => rotateHandle(layout()),
  problems: findProblems,
  // The registry's names as the editor has them, and why it has none if it failed.
  get controllers() { return { loaded: controllers.loaded, names: controllers.registry?.names ?? [], error: controllers.error }; },
};
