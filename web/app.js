// rilbed's control panel: a client of the run's Foxglove WebSocket (see foxglove.js).
// It draws what the run publishes and sends console commands and manual driving back; it
// keeps no state the run does not send, so any number of tabs show the same run.
import { prepareCanvas } from './canvas.js';
import { FoxgloveClient } from './foxglove.js';
import { wrapRadPi } from './angles.js';
import { makeProjection } from './projection.js';
import { marksInField } from './marks.js';
import { KHEPERA_BODY, bodyOnCanvas, reachAlong, robotBody } from './body.js';

const params = new URLSearchParams(location.search);
const token = params.get('token') || '';
const wsUrl = `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws?token=${encodeURIComponent(token)}`;

const IR_ANGLES_RAD = [90, 45, 10, -10, -45, -90, -170, 170].map((d) => (d * Math.PI) / 180);
const IR_COS = IR_ANGLES_RAD.map(Math.cos), IR_SIN = IR_ANGLES_RAD.map(Math.sin);
const IR_RANGE_M = 0.05; // what the IR ring sees; a reading of 1023 is touching
const TRAIL_POINTS = 400;
const HISTORY_PERIOD_S = 0.2;
const PLOT_POINTS = 1500; // at most, per robot and plot: a series that grows past it is halved
const LEGEND_ROBOTS = 20; // beyond it the formation plot's legend is a count
const TABLE_ROWS = 60; // the agent table shows at most this many robots

const $ = (id) => document.getElementById(id);

// ------------------------------------------------------------------ what the run said
const run = {
  world: null, status: null, poses: null, sensors: new Map(), detections: null,
  calibration: null, image: null, imageStamp: null, ended: false,
  bodies: new Map(), // id -> the robot's body as drawn (body.js's robotBody), from the world; a Khepera's if none
  trails: new Map(), // id -> [[x, y], ...] newest last
  history: new Map(), // id -> [[t, x, y], ...] every HISTORY_PERIOD_S
  formation: new Map(), // id -> [[t, d], ...]
  lastHistoryT: -Infinity,
};
// For tests and the curious: what the page holds now.
// stats: frames drawn, the last draw's milliseconds, frames in the last second, and how the
// trail layer was drawn (trailsLaid: laid anew for the view; trailsMoved: the layer laid
// for an earlier view, moved and scaled while the view moves); marks: the sensor models'
// marks the last frame drew; outlines and wheels: how many robots the last frame drew with
// their outline (not a disc) and with their wheels. bodyOf(id): robot id's body as drawn.
window.rilbed = { run, stats: { frames: 0, drawMs: 0, fps: 0, trailsLaid: 0, trailsMoved: 0, marks: 0, outlines: 0, wheels: 0 } };

// ------------------------------------------------------------------ the connection
const client = new FoxgloveClient(wsUrl);
const connection = $('connection');
client.onOpen = () => { connection.textContent = 'connected'; connection.className = 'pill ok'; };
client.onClose = () => {
  connection.textContent = 'disconnected'; connection.className = 'pill bad';
  showBanner(run.ended ? `${bannerText()} The server has closed.` : 'The server went away: this view no longer changes.',
    run.ended ? 'ended' : 'gone');
  stopDriving();
  // Nothing to steer any more.
  for (const c of document.querySelectorAll('#console button, #console input, #driving button, #driving select')) c.disabled = true;
  updateVisionControls();
};
client.onStatus = (level, message) => {
  if (level >= 1) note(`server: ${message}`, level === 2 ? 'error' : 'warning');
  visionStatus(level, message);
  // Another panel took our robot: we drive it no more (the server told us alone).
  if (driving.robot !== null && message.startsWith(`robot ${driving.robot} taken over by `)) {
    driving.keys.clear();
    if (driving.timer) { clearInterval(driving.timer); driving.timer = null; }
    driving.robot = null;
    updateDriveControls();
  }
};
client.subscribe(['/rilbed/world', '/rilbed/status', '/rilbed/poses', '/rilbed/sensors', '/rilbed/detections',
  '/rilbed/events', '/rilbed/summary', '/rilbed/console_reply', '/rilbed/camera', '/rilbed/camera_calibration']);
client.onMessage = (topic, tNs, m) => {
  switch (topic) {
    case '/rilbed/world': run.world = m; run.bodies = bodiesOf(m); fillRobotChoices(); $('scenario').textContent = m.scenario; break;
    case '/rilbed/status': onStatus(m); break;
    case '/rilbed/poses': onPoses(m); break;
    case '/rilbed/sensors': for (const r of m.robots) run.sensors.set(r.id, r); break;
    case '/rilbed/detections': run.detections = m; showFound(m); break;
    case '/rilbed/events': addEvent(m); break;
    case '/rilbed/summary': run.summary = m; break;
    case '/rilbed/console_reply': onReply(m); break;
    case '/rilbed/camera': onCameraFrame(m); break;
    case '/rilbed/camera_calibration': run.calibration = m; break;
    default: break;
  }
  requestDraw();
};

// Each robot's body (robot ID -> body.js's robotBody) from a world message: robots with
// the same body share one, a robot without one is a Khepera.
function bodiesOf(world) {
  const out = new Map(), alike = new Map();
  for (const r of world.robots || []) {
    const key = r.body ? JSON.stringify(r.body) : '';
    let body = alike.get(key);
    if (!body) alike.set(key, (body = key ? robotBody(r.body) : KHEPERA_BODY));
    out.set(r.id, body);
  }
  return out;
}
const bodyOf = (id) => run.bodies.get(id) || KHEPERA_BODY;
window.rilbed.bodyOf = bodyOf;

function onStatus(s) {
  const reset = run.status && s.t_s < run.status.t_s - 1e-9; // a reset starts over at 0
  if (reset) clearHistory();
  run.status = s;
  run.ended = s.state === 'ended';
  if (run.ended) showBanner(bannerText(), 'ended');
  else if (s.state === 'paused') showBanner(`Paused at t = ${s.t_s.toFixed(1)} s. Start resumes it.`, 'paused');
  else hideBanner();
  $('clock').textContent = `t = ${s.t_s.toFixed(1)} s`;
  setStat('state', s.state + (s.realtime ? ` (×${fmt(s.rt_factor)})` : ' (fast)'));
  setStat('seed', s.seed);
  setStat('mode', s.mode);
  setStat('robots', `${s.robots} (${s.real_robots} real)`);
  setStat('formed', s.formed ? `yes, at ${fmt(s.formation_time_s)} s` : 'no');
  setStat('collisions', s.collisions);
  setStat('loop latency', `${fmt(s.loop_latency_ms)} ms`);
  setStat('camera', s.real_robots ? `${fmt(s.camera_fps)} frames/s (${s.frames})` : '—');
  for (const r of document.querySelectorAll('input[name=mode]')) r.checked = r.value === s.mode;
  if (!sliderHeld) {
    $('rt-slider').value = Math.log10(s.rt_factor || 1);
    $('rt-value').textContent = fmt(s.rt_factor);
  }
  $('rt-slider').disabled = !s.realtime || s.real_robots > 0;
  $('pause').disabled = !s.realtime || s.state !== 'running';
  $('start').disabled = s.state !== 'paused';
  if (run.ended) {
    for (const c of document.querySelectorAll('#console button, #console input, #driving button')) c.disabled = true;
  }
  updateVisionControls();
}

function bannerText() {
  const s = run.status;
  if (!s) return 'The run has ended.';
  return `The run has ended (${s.ended_by || 'done'}) at t = ${s.t_s.toFixed(1)} s` +
    (s.formed ? `; the convoy formed at ${fmt(s.formation_time_s)} s.` : '; the convoy did not form.');
}

function onPoses(m) {
  if (run.poses && m.t_s < run.poses.t_s - 1e-9) clearHistory();
  run.poses = m;
  for (const r of m.robots) {
    let trail = run.trails.get(r.id);
    if (!trail) run.trails.set(r.id, (trail = []));
    const last = trail[trail.length - 1];
    if (!last || Math.hypot(last[0] - r.x_m, last[1] - r.y_m) > 0.003) {
      trail.push([r.x_m, r.y_m]);
      trail.pushed = (trail.pushed || 0) + 1; // points ever pushed: which are dots (every other)
      if (trail.length > TRAIL_POINTS) trail.splice(0, trail.length - TRAIL_POINTS);
    }
  }
  run.trailSeq = (run.trailSeq || 0) + 1; // the trails' layer lays what is new since
  if (m.t_s - run.lastHistoryT >= HISTORY_PERIOD_S) {
    run.lastHistoryT = m.t_s;
    // Each robot's formation series: in a small run every robot has one (its legend), in a
    // large one only the robots that have followed. The distance ahead (every robot against
    // every other) is worked out for followers only, so not at all in a run without a convoy.
    const few = m.robots.length <= LEGEND_ROBOTS;
    // A trajectory point is kept when the robot has moved a pixel of the plot or 1 cm.
    const step = Math.max(0.01, 1 / (trajectoryPlot.scale || Infinity));
    for (const r of m.robots) {
      let pts = run.history.get(r.id);
      if (!pts) run.history.set(r.id, (pts = []));
      const last = pts[pts.length - 1];
      if (!last || Math.abs(last[1] - r.x_m) >= step || Math.abs(last[2] - r.y_m) >= step) {
        pts.push([m.t_s, r.x_m, r.y_m]);
        if (pts.length > PLOT_POINTS) thin(pts, () => false);
      }
      const follows = r.behaviour === 'follow';
      let f = run.formation.get(r.id);
      if (!f) {
        if (!follows && !few) continue;
        run.formation.set(r.id, (f = []));
      }
      f.push([m.t_s, follows ? distanceAhead(r, m.robots) : null]);
      if (f.length > PLOT_POINTS) thin(f, (p) => p[1] === null);
    }
    plotsDirty = true;
  }
  updateAgentTable(m.robots);
}

// The distance to the nearest robot within 60 degrees of straight ahead (what a follower
// keeps to its leader), or null.
function distanceAhead(r, robots) {
  let best = null;
  for (const o of robots) {
    if (o.id === r.id) continue;
    const dx = o.x_m - r.x_m, dy = o.y_m - r.y_m;
    const d = Math.hypot(dx, dy);
    const off = Math.abs(wrapRadPi(Math.atan2(dy, dx) - r.theta_rad));
    if (off <= Math.PI / 3 && (best === null || d < best)) best = d;
  }
  return best;
}

// Halves a plot's series in place, keeping its first and last points (so its whole time span)
// and every point `keep` says must stay (the gaps in a follower's line).
function thin(points, keep) {
  let n = 0;
  for (let i = 0; i < points.length; ++i) {
    if (i % 2 === 0 || i === points.length - 1 || keep(points[i])) points[n++] = points[i];
  }
  points.length = n;
}

function clearHistory() {
  run.trails.clear(); run.trailEpoch = (run.trailEpoch || 0) + 1; run.history.clear(); run.formation.clear(); run.lastHistoryT = -Infinity;
  trajectoryPlot.key = '';
  plotsDirty = true;
}

function onCameraFrame(m) {
  const stamp = m.timestamp;
  const img = new Image();
  img.onload = () => { run.image = img; run.imageStamp = stamp; requestDraw(); };
  img.src = `data:image/${m.format || 'jpeg'};base64,${m.data}`;
}

// ------------------------------------------------------------------ status, events
function setStat(name, value) {
  const stats = $('stats');
  let dd = stats.querySelector(`dd[data-stat="${name}"]`);
  if (!dd) {
    const dt = document.createElement('dt'); dt.textContent = name;
    dd = document.createElement('dd'); dd.dataset.stat = name;
    stats.append(dt, dd);
  }
  dd.textContent = value;
}

// The agent table: one row per robot, or with many robots at most TABLE_ROWS of them (the
// real ones first, then the one driven or chosen to drive, then by ID; those matching the ID
// filter if one is typed) and a line saying how many more. A cell is written only when its
// text changes, so that a message that changes nothing lays nothing out again.
const agentRows = new Map(); // id -> { row, text: [4 strings], cls }
let agentShown = ''; // the IDs shown, in order, as a key
function updateAgentTable(robots) {
  const body = document.querySelector('#agents tbody');
  const filterBox = $('agent-filter'), more = $('agents-more');
  const filter = filterBox.value.trim();
  const noFilter = robots.length <= TABLE_ROWS && !filter;
  if (filterBox.hidden !== noFilter) filterBox.hidden = noFilter;
  let shown = filter ? robots.filter((r) => String(r.id).includes(filter)) : robots;
  const matching = shown.length;
  if (shown.length > TABLE_ROWS) {
    const choice = $('drive-robot').value, chosen = driving.robot ?? (choice === '' ? null : Number(choice));
    const rank = (r) => (r.real ? 0 : r.id === chosen ? 1 : 2);
    shown = [...shown].sort((x, y) => rank(x) - rank(y) || x.id - y.id).slice(0, TABLE_ROWS);
  }
  shown = [...shown].sort((x, y) => x.id - y.id);
  const key = shown.map((r) => r.id).join(',');
  if (key !== agentShown) {
    agentShown = key;
    const keep = new Set(shown.map((r) => r.id));
    for (const [id, a] of agentRows) if (!keep.has(id)) { a.row.remove(); agentRows.delete(id); }
    for (const r of shown) {
      let a = agentRows.get(r.id);
      if (!a) {
        const row = document.createElement('tr'); row.dataset.id = r.id;
        for (let i = 0; i < 4; ++i) row.insertCell();
        agentRows.set(r.id, (a = { row, text: ['', '', '', ''], cls: '' }));
      }
      body.append(a.row); // in order
    }
  }
  for (const r of shown) {
    const a = agentRows.get(r.id);
    const health = r.real ? (r.health || 'ok') : '—';
    const text = [String(r.id), r.real ? (r.seen ? 'real' : 'real, unseen') : 'virtual', r.behaviour, health];
    for (let i = 0; i < 4; ++i) if (a.text[i] !== text[i]) a.row.cells[i].textContent = a.text[i] = text[i];
    const cls = !r.real ? '' : health === 'ok' ? 'health-ok' : /lost/.test(health) ? 'health-bad' : 'health-warn';
    if (a.cls !== cls) a.row.cells[3].className = a.cls = cls;
  }
  const hidden = matching - shown.length;
  const line = hidden > 0 ? `… ${hidden} more robot${hidden === 1 ? '' : 's'}` : filter && !matching ? `no robot's ID contains ${filter}` : '';
  if (more.textContent !== line) more.textContent = line;
  if (more.hidden !== !line) more.hidden = !line;
}
$('agent-filter').addEventListener('input', () => { if (run.poses) updateAgentTable(run.poses.robots); });

function addEvent(e) {
  const list = $('events');
  const li = document.createElement('li');
  li.textContent = `${e.t_s.toFixed(1)} s  ${e.kind}${e.id ? ' ' + e.id : ''}${e.other ? '/' + e.other : ''}: ${e.detail}`;
  list.prepend(li);
  while (list.children.length > 200) list.lastChild.remove();
}

function note(text, kind = 'info') {
  const reply = $('reply');
  reply.textContent = text;
  reply.style.color = kind === 'error' ? 'var(--danger)' : kind === 'warning' ? 'var(--warn)' : '';
}

function onReply(m) {
  note(`${m.accepted ? '✓' : '✗'} ${m.reason}`, m.accepted ? 'info' : 'error');
}

function showBanner(text, kind) { const b = $('banner'); b.textContent = text; b.className = kind; b.hidden = false; }
function hideBanner() { $('banner').hidden = true; }

// Three significant digits, without trailing zeros after the point (100 stays 100).
const fmt = (x) => {
  if (x === null || x === undefined || !isFinite(x)) return '—';
  const v = Number(x);
  if (Math.abs(v) >= 999.5) return String(Math.round(v));
  const t = v.toPrecision(3);
  return t.includes('.') ? t.replace(/0+$/, '').replace(/\.$/, '') : t;
};

// ------------------------------------------------------------------ console
function command(name, ...args) {
  if (!client.publish('/rilbed/console', { command: name, args: args.map(String) }, 'rilbed.console')) {
    note('not connected', 'error');
  }
}
for (const b of document.querySelectorAll('#console button[data-command]')) {
  b.addEventListener('click', () => {
    if (b.dataset.command === 'exit' && !confirm('End the run?')) return;
    command(b.dataset.command);
  });
}
let sliderHeld = false;
const slider = $('rt-slider');
slider.addEventListener('input', () => { sliderHeld = true; $('rt-value').textContent = fmt(10 ** Number(slider.value)); });
slider.addEventListener('change', () => {
  sliderHeld = false;
  command('rt-factor', fmt(10 ** Number(slider.value)));
});
for (const r of document.querySelectorAll('input[name=mode]')) r.addEventListener('change', () => command('mode', r.value));

// ------------------------------------------------------------------ manual driving
// A dead man's switch: while a key is held the page sends the speeds every 100 ms; the
// server stops the robot when they stop for 300 ms, when this tab closes, or when another
// client takes the robot.
const driving = { robot: null, keys: new Set(), timer: null };
const DRIVE_KEYS = ['ArrowUp', 'ArrowDown', 'ArrowLeft', 'ArrowRight'];

function fillRobotChoices() {
  const select = $('drive-robot');
  const ids = (run.world?.robots || []).map((r) => `${r.id}${r.real ? ' (real)' : ''}`);
  const now = [...select.options].map((o) => o.textContent);
  if (ids.join() === now.join()) return;
  const chosen = select.value;
  select.replaceChildren(...(run.world?.robots || []).map((r) => new Option(`${r.id}${r.real ? ' (real)' : ''}`, r.id)));
  if (chosen) select.value = chosen;
}

function wheelSpeeds() {
  const v = Number($('drive-speed').value);
  let forward = 0, turn = 0;
  if (driving.keys.has('ArrowUp')) forward += 1;
  if (driving.keys.has('ArrowDown')) forward -= 1;
  if (driving.keys.has('ArrowLeft')) turn += 1;
  if (driving.keys.has('ArrowRight')) turn -= 1;
  const clamp = (x) => Math.max(-127, Math.min(127, Math.round(x)));
  return [clamp(v * (forward - 0.6 * turn)), clamp(v * (forward + 0.6 * turn))];
}

function sendDrive() {
  if (driving.robot === null) return;
  const [left, right] = wheelSpeeds();
  client.publish('/rilbed/drive', { id: driving.robot, left, right }, 'rilbed.drive');
}

function keysChanged() {
  for (const b of document.querySelectorAll('#drive-pad button')) b.classList.toggle('held', driving.keys.has(b.dataset.key));
  if (driving.robot === null) return;
  if (driving.keys.size && !driving.timer) driving.timer = setInterval(sendDrive, 100);
  if (!driving.keys.size && driving.timer) { clearInterval(driving.timer); driving.timer = null; }
  sendDrive(); // at once: a press moves, a release stops, without waiting for the tick
}

function takeRobot() {
  driving.robot = Number($('drive-robot').value);
  sendDrive(); // holds it, standing (no key yet)
  updateDriveControls();
  $('view').focus();
}

function stopDriving() {
  driving.keys.clear();
  if (driving.timer) { clearInterval(driving.timer); driving.timer = null; }
  if (driving.robot !== null && client.open) client.publish('/rilbed/drive', { id: driving.robot, release: true }, 'rilbed.drive');
  driving.robot = null;
  updateDriveControls();
}

function updateDriveControls() {
  $('drive-take').disabled = driving.robot !== null;
  $('drive-release').disabled = driving.robot === null;
  $('drive-state').textContent = driving.robot === null ? '' : `driving robot ${driving.robot}`;
  for (const b of document.querySelectorAll('#drive-pad button')) b.classList.toggle('held', driving.keys.has(b.dataset.key));
}

$('drive-take').addEventListener('click', takeRobot);
$('drive-release').addEventListener('click', stopDriving);
$('drive-speed').addEventListener('input', () => { $('drive-speed-value').textContent = $('drive-speed').value; });
document.addEventListener('keydown', (e) => {
  if (!DRIVE_KEYS.includes(e.key) || driving.robot === null || e.target.matches('input, select, textarea')) return;
  e.preventDefault();
  if (!driving.keys.has(e.key)) { driving.keys.add(e.key); keysChanged(); }
});
document.addEventListener('keyup', (e) => {
  if (driving.keys.delete(e.key)) { e.preventDefault(); keysChanged(); }
});
window.addEventListener('blur', () => { if (driving.keys.size) { driving.keys.clear(); keysChanged(); } });
for (const b of document.querySelectorAll('#drive-pad button')) {
  const press = (e) => { e.preventDefault(); if (driving.robot !== null && !driving.keys.has(b.dataset.key)) { driving.keys.add(b.dataset.key); keysChanged(); } };
  const release = () => { if (driving.keys.delete(b.dataset.key)) keysChanged(); };
  b.addEventListener('pointerdown', press);
  b.addEventListener('pointerup', release);
  b.addEventListener('pointerleave', release);
  b.addEventListener('pointercancel', release);
}
updateDriveControls();

// ------------------------------------------------------------------ vision settings
// The camera pipeline's settings are the run's parameters (Foxglove's getParameters /
// setParameters / subscribeParameterUpdates). A slider sends what it is moved to, a few
// times a second at most, the newest value winning; the readouts, and the sliders once let
// go, show what the run answers, so a refusal or another client's change shows at once.
const VISION_PERIOD_MS = 250;
const VISION = [
  { key: 'brightness', label: 'brightness (grey levels)', min: -128, max: 128, step: 1, whole: true, def: 0,
    tip: 'Grey levels added to every pixel before detection (after contrast); the camera view shows the result. ' +
      'Raising it lightens a dark image; too far and a light floor and the markers\' white clip to 255, and their edges go.' },
  { key: 'contrast', label: 'contrast (gain)', min: 0.2, max: 5, log: true, def: 1,
    tip: 'Gain about mid-grey 128, applied before brightness; the camera view shows the result. Raising it parts a washed-out ' +
      'marker\'s black from its white; too far and dark and light parts clip to 0 and 255, and the floor\'s noise grows with it.' },
  { key: 'threshold', label: 'threshold (grey levels)', min: 1, max: 255, step: 1, whole: true, def: 24,
    tip: 'The least local contrast for a pixel to count as dark or bright in the marker search. Raising it ignores floor mottling ' +
      'and shadows and searches less; too high and faint, blurred or badly lit markers are missed.' },
  { key: 'min_diameter_px', label: 'min diameter (px)', min: 6, max: 4000, log: true, whole: true, def: 18,
    tip: 'The smallest marker diameter looked for. Raising it skips small blobs (a faster search, fewer false finds); ' +
      'markers that look smaller than this, far from the camera or in a low resolution, are missed.' },
  { key: 'max_diameter_px', label: 'max diameter (px)', min: 6, max: 4000, log: true, whole: true, def: 480,
    tip: 'The largest marker diameter looked for; it must stay above the minimum. Raising it finds markers close to the camera, ' +
      'at the cost of a longer search over large regions.' },
  { key: 'min_score', label: 'min score (0–1)', min: 0, max: 1, step: 0.01, def: 0.75,
    tip: 'The least decoding similarity for a marker to take an ID. Raising it avoids wrong IDs; too high and worn, blurred ' +
      'or tilted markers get none (at 1 hardly any marker does).' },
].map((p) => ({ ...p, name: `vision.${p.key}` }));
const VISION_NAMES = VISION.map((p) => p.name);

const vision = {
  available: false, reason: 'asking the run for its vision settings…',
  values: {},           // name -> the run's value (what parameterValues said last)
  pending: new Map(),   // name -> a value not sent yet (newest wins)
  inFlight: new Map(),  // name -> requests sent and not answered
  sent: new Map(),      // name -> the value last sent
  held: new Set(),      // sliders being moved
  lastSent: -Infinity, timer: null,
  refusal: null,        // {at, names, reason}: the last request the run refused
  lastError: null,      // {at, message}: the server's last error status
};

// Slider position <-> value: contrast and the diameters on a log scale.
const toSlider = (p, v) => (p.log ? Math.log10(v) : v);
function fromSlider(p, x) {
  let v = p.log ? 10 ** x : x;
  v = p.whole ? Math.round(v) : Number(v.toFixed(2));
  return Math.min(p.max, Math.max(p.min, v));
}
// Up to four significant digits, no trailing zeros (1.5, 0.75, 480).
const fmtParam = (v) => (typeof v === 'number' && isFinite(v) ? String(Number(v.toPrecision(4))) : '—');

for (const p of VISION) {
  const row = document.createElement('label');
  row.className = 'vision-param'; row.title = p.tip; row.dataset.param = p.name;
  const text = document.createElement('span'); text.textContent = p.label;
  const input = document.createElement('input');
  input.type = 'range'; input.id = `vision-${p.key}`; input.setAttribute('aria-label', p.label);
  input.min = toSlider(p, p.min); input.max = toSlider(p, p.max); input.step = p.log ? 'any' : p.step;
  input.value = toSlider(p, p.def);
  const out = document.createElement('output'); out.textContent = '—';
  row.append(text, input, out);
  $('vision-params').append(row);
  p.input = input; p.output = out;
  input.addEventListener('input', () => { vision.held.add(p.name); wishVision(p.name, fromSlider(p, Number(input.value))); });
  input.addEventListener('change', () => {
    vision.held.delete(p.name);
    const value = fromSlider(p, Number(input.value));
    if (value !== vision.sent.get(p.name) || vision.values[p.name] !== value) wishVision(p.name, value);
    else showVisionValues(); // already the run's: the slider may follow it again
  });
}
$('vision-defaults').addEventListener('click', () => { for (const p of VISION) wishVision(p.name, p.def); });

function wishVision(name, value) {
  if (vision.pending.get(name) === value) return;
  vision.pending.set(name, value);
  if (vision.timer) return;
  vision.timer = setTimeout(flushVision, Math.max(0, vision.lastSent + VISION_PERIOD_MS - performance.now()));
}

function flushVision() {
  vision.timer = null;
  if (!vision.pending.size) return;
  const parameters = [...vision.pending].map(([name, value]) => ({ name, value }));
  vision.pending.clear();
  vision.lastSent = performance.now();
  setVision(parameters).catch(() => {}); // a closed connection says so on the page already
}

// One setParameters request (all or nothing); resolves to {values, refused, reason}.
async function setVision(parameters) {
  for (const { name, value } of parameters) {
    vision.inFlight.set(name, (vision.inFlight.get(name) || 0) + 1);
    vision.sent.set(name, value);
  }
  const sentAt = performance.now();
  try {
    const after = await client.setParameters(parameters);
    applyVisionValues(after);
    const refused = parameters.filter(({ name, value }) => {
      const now = after.find((a) => a.name === name)?.value;
      return typeof now !== 'number' || Math.abs(now - value) > 1e-6 * Math.max(1, Math.abs(value));
    });
    if (refused.length) {
      const recent = vision.lastError && vision.lastError.at >= sentAt - 50 ? vision.lastError.message : null;
      vision.refusal = { at: performance.now(), names: refused.map((p) => p.name), reason: recent };
      showVisionRefusal();
    } else {
      vision.refusal = null;
      $('vision-reply').textContent = '';
    }
    return { values: { ...vision.values }, refused: refused.map((p) => p.name), reason: vision.refusal?.reason ?? null };
  } catch (e) {
    visionReply(`✗ ${e.message}`, 'error');
    throw e;
  } finally {
    for (const { name } of parameters) vision.inFlight.set(name, vision.inFlight.get(name) - 1);
    showVisionValues();
  }
}

function showVisionRefusal() {
  const r = vision.refusal;
  const kept = r.names.map((n) => `${n.slice('vision.'.length)} ${fmtParam(vision.values[n])}`).join(', ');
  visionReply(`✗ ${r.reason || 'refused'} (kept ${kept})`, 'error');
}

function visionReply(text, kind) {
  const reply = $('vision-reply');
  reply.textContent = text;
  reply.style.color = kind === 'error' ? 'var(--danger)' : '';
}

// The server's error statuses: the reason for a refusal, which may come just after its answer.
function visionStatus(level, message) {
  if (level < 2) return;
  vision.lastError = { at: performance.now(), message };
  if (vision.refusal && !vision.refusal.reason && performance.now() - vision.refusal.at < 2000) {
    vision.refusal.reason = message;
    showVisionRefusal();
  }
}

// A parameter without a value (or null) is gone: the run has lost its camera. One that
// comes later (the run's first status with its camera) makes the section usable.
function applyVisionValues(parameters) {
  for (const { name, value } of parameters) {
    if (!VISION_NAMES.includes(name)) continue;
    if (typeof value === 'number') vision.values[name] = value;
    else if (value === undefined || value === null) delete vision.values[name];
  }
  const available = VISION_NAMES.some((n) => n in vision.values);
  if (available !== vision.available) {
    vision.available = available;
    if (!available) vision.reason = 'No camera in this run: nothing to tune.';
    updateVisionControls();
  }
  showVisionValues();
}

function showVisionValues() {
  for (const p of VISION) {
    const v = vision.values[p.name];
    p.output.textContent = fmtParam(v);
    // A slider follows the run unless it is being moved or has a value on its way.
    if (v !== undefined && !vision.held.has(p.name) && !vision.pending.has(p.name) && !(vision.inFlight.get(p.name) > 0)) {
      p.input.value = toSlider(p, v);
    }
  }
  const all = VISION.every((p) => vision.values[p.name] !== undefined);
  $('vision-yaml').textContent = all ? `vision: {${VISION.map((p) => `${p.key}: ${fmtParam(vision.values[p.name])}`).join(', ')}}` : '';
  $('vision-yaml').parentElement.hidden = !all;
}

function updateVisionControls() {
  const usable = vision.available && client.open && !run.ended;
  $('vision').classList.toggle('unavailable', !vision.available);
  $('vision-reason').hidden = vision.available;
  $('vision-reason').textContent = vision.reason;
  for (const c of document.querySelectorAll('#vision input, #vision button')) {
    c.disabled = !usable || (c.type === 'range' && vision.values[c.closest('[data-param]').dataset.param] === undefined);
  }
}

function showFound(m) {
  const ids = m.detections.map((d) => d.id).sort((a, b) => a - b);
  const text = `found ${ids.length ? `${ids.length} (ID ${ids.join(', ')})` : 'no marker'} in ${fmt(m.process_ms)} ms`;
  const found = $('vision-found');
  if (found.textContent !== text) found.textContent = text;
}

client.onServerInfo = async () => {
  if (!client.can('parameters')) {
    vision.reason = 'This server has no settings to tune (no "parameters" capability).';
    updateVisionControls();
    return;
  }
  // Every parameterValues (answers and updates) goes to the section. Subscribed first, so
  // that settings the run comes to have after the answer (its camera starting) show too.
  client.onParameterValues = (parameters) => applyVisionValues(parameters);
  if (client.can('parametersSubscribe')) client.subscribeParameterUpdates(VISION_NAMES);
  try {
    await client.getParameters(VISION_NAMES);
    if (!vision.available) vision.reason = 'No camera in this run: nothing to tune.';
  } catch (e) {
    if (!vision.available) vision.reason = `The run did not say its vision settings (${e.message}).`;
  }
  updateVisionControls();
};
updateVisionControls();

// For tests: the settings as the run last said, and requests as the sliders make them.
window.rilbed.vision = {
  get values() { return { ...vision.values }; },
  get available() { return vision.available; },
  get reason() { return vision.reason; },
  get refusal() { return vision.refusal && { names: vision.refusal.names, reason: vision.refusal.reason }; },
  set: (values) => setVision(Object.entries(values).map(([key, value]) => ({ name: key.startsWith('vision.') ? key : `vision.${key}`, value }))),
  defaults: Object.fromEntries(VISION.map((p) => [p.key, p.def])),
};

// ------------------------------------------------------------------ the live view
const canvas = $('view');
const ctx = canvas.getContext('2d');
const overlays = {};
for (const box of document.querySelectorAll('[data-overlay]')) {
  overlays[box.dataset.overlay] = box.checked;
  box.addEventListener('change', () => { overlays[box.dataset.overlay] = box.checked; requestDraw(); });
}
$('trail-style').addEventListener('change', requestDraw);
// The view: zoom and pan on top of a fit of the field (or the camera image) to the canvas.
const view = { zoom: 1, panX: 0, panY: 0 };
$('fit').addEventListener('click', fitView);
canvas.addEventListener('dblclick', fitView);
function fitView() { view.zoom = 1; view.panX = 0; view.panY = 0; requestDraw(); }
canvas.addEventListener('wheel', (e) => {
  e.preventDefault();
  const r = canvas.getBoundingClientRect();
  const mx = e.clientX - r.left, my = e.clientY - r.top;
  const k = Math.exp(-e.deltaY * 0.0015);
  const zoom = Math.min(50, Math.max(0.2, view.zoom * k));
  const f = zoom / view.zoom;
  view.panX = mx - (mx - view.panX) * f;
  view.panY = my - (my - view.panY) * f;
  view.zoom = zoom;
  requestDraw();
}, { passive: false });
let drag = null;
canvas.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY }; canvas.setPointerCapture(e.pointerId); });
canvas.addEventListener('pointermove', (e) => {
  if (!drag) return;
  view.panX += e.clientX - drag.x; view.panY += e.clientY - drag.y;
  drag = { x: e.clientX, y: e.clientY };
  requestDraw();
});
canvas.addEventListener('pointerup', () => { drag = null; });

// Where field point (x, y) metres lands on the canvas: through the camera's homography when
// the camera image is shown, else a fit of the field; then zoom and pan (`vw`: the view's
// zoom, panX, panY; the current view unless another is given, e.g. the trail layer's).
function projection(width, height, vw = view) {
  const calibration = overlays.camera && run.image && run.calibration ? run.calibration : null;
  return makeProjection(width, height, vw, { field: run.world, calibration });
}

let drawPending = false;
function requestDraw() {
  if (drawPending) return;
  drawPending = true;
  requestAnimationFrame(draw);
}

let fpsWindow = [];
function draw(now) {
  drawPending = false;
  const t0 = performance.now();
  const [, w, h] = prepareCanvas(canvas);
  const P = projection(w, h);
  window.rilbed.project = P.project; // field metres -> canvas CSS pixels, as drawn now (for tests)
  if (P.base.camera) {
    ctx.save();
    ctx.translate(view.panX + P.z * P.base.ox, view.panY + P.z * P.base.oy);
    ctx.scale(P.z * P.base.s, P.z * P.base.s);
    ctx.drawImage(run.image, 0, 0);
    ctx.restore();
  }
  if (run.world && overlays.field) drawField(P);
  if (overlays.trails) drawTrails(P);
  window.rilbed.stats.outlines = window.rilbed.stats.wheels = 0; // (drawRobots counts them)
  if (run.poses) {
    if (overlays.tracks || overlays.ranges || overlays.beacons || overlays.ir) drawSensors(P);
    if (overlays.robots) drawRobots(P);
    window.rilbed.stats.marks = overlays.marks ? drawMarks(P) : 0; // over the robots: marks sit inside a robot's outline
  }
  if (overlays.detections && run.detections) drawDetections(P);
  if (plotsDirty) drawPlots();
  const stats = window.rilbed.stats;
  stats.frames += 1;
  stats.drawMs = performance.now() - t0;
  fpsWindow.push(now);
  while (fpsWindow.length && now - fpsWindow[0] > 1000) fpsWindow.shift();
  stats.fps = fpsWindow.length;
}

function polyline(P, points, close) {
  ctx.beginPath();
  points.forEach((p, i) => { const [u, v] = P.project(p.x_m ?? p[0], p.y_m ?? p[1]); if (i) ctx.lineTo(u, v); else ctx.moveTo(u, v); });
  if (close) ctx.closePath();
}

function drawField(P) {
  const W = run.world;
  for (const t of W.tracks) {
    ctx.strokeStyle = 'rgba(40,40,40,0.35)';
    ctx.lineWidth = Math.max(1, t.width_m * P.scaleAt(t.points[0]?.x_m ?? 0, t.points[0]?.y_m ?? 0));
    ctx.lineJoin = 'round';
    polyline(P, t.points, false); ctx.stroke();
  }
  ctx.fillStyle = 'rgba(90,90,90,0.45)'; ctx.strokeStyle = '#555'; ctx.lineWidth = 1.5;
  for (const o of W.obstacles) { polyline(P, o, true); ctx.fill(); ctx.stroke(); }
  ctx.strokeStyle = '#1a9e2a'; ctx.lineWidth = 2.5;
  polyline(P, [[0, 0], [W.width_m, 0], [W.width_m, W.height_m], [0, W.height_m]], true); ctx.stroke();
  W.beacons.forEach((b, i) => {
    const [u, v] = P.project(b.x_m, b.y_m);
    ctx.fillStyle = '#e0a800'; ctx.beginPath(); ctx.arc(u, v, 6, 0, 2 * Math.PI); ctx.fill();
    ctx.fillStyle = '#000'; ctx.font = '11px system-ui'; ctx.fillText(`B${i + 1}`, u + 8, v - 6);
  });
}

// The trails' dots (2 x 2 pixels, every other trail point) are laid pixel by pixel into an
// image of the canvas's size, put on the canvas in one call: 1,000 robots' trails are 200,000
// dots, which fillRect (or a path of them) draws at a few frames a second without a GPU. Each
// dot lies over what is there at its colour's alpha, as fillRect lays it, on whole CSS pixels.
const TRAIL_COLOURS = [[210, 40, 40, 0.4], [36, 86, 199, 0.45]]; // a virtual robot's, a real one's (RGBA)
// over[a]: the alpha (0-255) of a dot of that colour laid over alpha a.
const TRAIL_OVER = TRAIL_COLOURS.map(([, , , alpha]) => Uint8Array.from({ length: 256 }, (_, a) => Math.round(255 * alpha + a * (1 - alpha))));
// The layer is kept between frames, in canvas CSS pixels: each new pose message lays only
// its new dots (and re-makes only their pixels); it is laid anew from the trails when the
// projection changes (zoom, pan, size, camera image), when the trails are cleared or the
// real robots change, and every TRAIL_REBUILD pose messages, so that dots older than the
// trails' 400 points go (they stay at most TRAIL_REBUILD messages, 4 s, too long).
// While the view moves (zoom, pan), laying it anew each frame would cost the frame rate (a
// few tens of milliseconds for 200,000 dots): the layer laid for the view before is drawn
// moved and scaled to the new view (coarser for a moment), new dots go into it in its own
// view, and it is laid anew for the view once the view has rested VIEW_REST_MS.
const TRAIL_REBUILD = 40;
const VIEW_REST_MS = 150;
const trailLayer = { canvas: document.createElement('canvas'), w: 0, h: 0, key: '', laid: new Map() };
const TRAIL_RGB = TRAIL_COLOURS.map(([r, g, b]) => (b << 16) | (g << 8) | r);

function drawTrails(P) {
  const outline = $('trail-style').value === 'outline';
  const realIds = new Set();
  for (const r of run.poses?.robots || []) if (r.real) realIds.add(r.id);
  const css = ([r, g, b, a]) => `rgba(${r},${g},${b},${a})`;
  if (outline) {
    for (const [id, trail] of run.trails) {
      if (trail.length < 2) continue;
      ctx.strokeStyle = css(TRAIL_COLOURS[realIds.has(id) ? 1 : 0]);
      ctx.lineWidth = 1.5; polyline(P, trail, false); ctx.stroke();
    }
    return;
  }
  const L = trailLayer, W = Math.ceil(P.width), H = Math.ceil(P.height);
  if (W < 1 || H < 1) return;
  if (L.w !== W || L.h !== H) {
    L.canvas.width = L.w = W; L.canvas.height = L.h = H;
    L.alpha = [new Uint8Array(W * H), new Uint8Array(W * H)];
    L.image = new ImageData(W, H);
    L.pixels = new Uint32Array(L.image.data.buffer); // RGBA bytes: 0xAABBGGRR (little-endian)
    L.key = '';
  }
  // The layer's own view: the current one, or while the view moves the one it was laid for.
  const B = P.base, now = performance.now();
  const viewNow = `${view.zoom} ${view.panX} ${view.panY}`;
  if (viewNow !== L.seenView) { L.seenView = viewNow; L.viewMovedAt = now; }
  const moving = now - (L.viewMovedAt ?? -Infinity) < VIEW_REST_MS;
  const key = [W, H, B.s, B.ox, B.oy, B.camera, B.camera && [run.calibration.width_px, run.calibration.height_px, ...run.calibration.field_to_image].join(','),
    run.trailEpoch || 0, [...realIds].join(',')].join(' ');
  const sameView = L.view && L.view.zoom === view.zoom && L.view.panX === view.panX && L.view.panY === view.panY;
  const follow = key === L.key && !sameView && moving;
  const seq = run.trailSeq || 0;
  const rebuild = key !== L.key || (!sameView && !follow) || (!moving && seq - L.builtSeq >= TRAIL_REBUILD);
  if (follow) { // laid anew once the view rests
    clearTimeout(L.restTimer);
    L.restTimer = setTimeout(requestDraw, VIEW_REST_MS + 10);
  }
  const LP = follow ? projection(P.width, P.height, L.view) : P;
  const A = LP.affine;
  // The layer onto the canvas, moved from its view to the current one: zoom and pan map
  // canvas pixels affinely (camera or not), u' = pan' + (z' / z) (u - pan).
  const blit = () => {
    ctx.save(); ctx.imageSmoothingEnabled = false;
    if (follow) {
      const f = view.zoom / L.view.zoom;
      ctx.translate(view.panX - f * L.view.panX, view.panY - f * L.view.panY); ctx.scale(f, f);
    }
    ctx.drawImage(L.canvas, 0, 0, W, H); ctx.restore();
  };
  const stats = window.rilbed.stats;
  if (follow) stats.trailsMoved += 1;
  if (rebuild) {
    stats.trailsLaid += 1;
    L.alpha[0].fill(0); L.alpha[1].fill(0);
    L.laid.clear(); L.key = key; L.builtSeq = seq;
    L.view = { zoom: view.zoom, panX: view.panX, panY: view.panY };
  } else if (seq === L.seq) { // nothing new
    blit();
    return;
  }
  L.seq = seq;
  const [v0, v1] = L.alpha, out = L.pixels;
  // Pixel k's colour from its two alphas: real robots' dots over virtual ones'.
  const compose = (k) => {
    const a0 = v0[k], a1 = v1[k];
    if (!a1) out[k] = a0 ? ((a0 << 24) | TRAIL_RGB[0]) >>> 0 : 0;
    else if (!a0) out[k] = ((a1 << 24) | TRAIL_RGB[1]) >>> 0;
    else {
      const under = (a0 * (255 - a1)) / 255, a = a1 + under;
      const mix = (i) => Math.round((TRAIL_COLOURS[1][i] * a1 + TRAIL_COLOURS[0][i] * under) / a);
      out[k] = ((Math.round(a) << 24) | (mix(2) << 16) | (mix(1) << 8) | mix(0)) >>> 0;
    }
  };
  let minX = W, minY = H, maxX = -1, maxY = -1; // the pixels changed
  for (const [id, trail] of run.trails) {
    const pushed = trail.pushed || 0, laid = L.laid.get(id) || 0;
    if (pushed === laid) continue;
    L.laid.set(id, pushed);
    const kind = realIds.has(id) ? 1 : 0, alpha = L.alpha[kind], over = TRAIL_OVER[kind];
    // Point i is push number first + i; the even ones are dots.
    const first = pushed - trail.length;
    let i = Math.max(0, laid - first);
    if ((first + i) % 2) ++i;
    for (; i < trail.length; i += 2) {
      const x = trail[i][0], y = trail[i][1];
      let u, v;
      if (A) { u = A.ax * x + A.bx; v = A.ay * y + A.by; } else [u, v] = LP.project(x, y);
      const x0 = Math.round(u - 1), y0 = Math.round(v - 1); // the dot's top left pixel
      if (x0 >= 0 && y0 >= 0 && x0 < W - 1 && y0 < H - 1) {
        const k = y0 * W + x0;
        alpha[k] = over[alpha[k]]; alpha[k + 1] = over[alpha[k + 1]];
        alpha[k + W] = over[alpha[k + W]]; alpha[k + W + 1] = over[alpha[k + W + 1]];
        if (!rebuild) { compose(k); compose(k + 1); compose(k + W); compose(k + W + 1); }
      } else if (x0 >= -1 && y0 >= -1 && x0 < W && y0 < H) { // across an edge
        for (let py = Math.max(0, y0); py < Math.min(H, y0 + 2); ++py) {
          for (let px = Math.max(0, x0), k = py * W + px; px < Math.min(W, x0 + 2); ++px, ++k) {
            alpha[k] = over[alpha[k]];
            if (!rebuild) compose(k);
          }
        }
      } else continue;
      if (x0 < minX) minX = x0; if (y0 < minY) minY = y0;
      if (x0 + 1 > maxX) maxX = x0 + 1; if (y0 + 1 > maxY) maxY = y0 + 1;
    }
  }
  const lctx = L.canvas.getContext('2d');
  if (rebuild) {
    for (let k = 0; k < out.length; ++k) {
      const a0 = v0[k], a1 = v1[k];
      if (!a1) out[k] = a0 ? ((a0 << 24) | TRAIL_RGB[0]) >>> 0 : 0;
      else compose(k);
    }
    lctx.putImageData(L.image, 0, 0);
  } else if (maxX >= 0) {
    minX = Math.max(0, minX); minY = Math.max(0, minY);
    lctx.putImageData(L.image, 0, 0, minX, minY, Math.min(W - 1, maxX) - minX + 1, Math.min(H - 1, maxY) - minY + 1);
  }
  blit();
}

const MANY_LABELS = 200, LABEL_SPACING_PX = 60;

// Each robot is its body (body.js): its disc or its outline turned to its heading, its two
// wheels as dark rectangles under it, and its heading mark. The virtual robots are one path
// stroked once, the wheels one path filled once, then every label: a thousand robots are a
// few calls, not thousands. Robots off the canvas are not drawn.
const WHEEL_CSS = 'rgba(40,40,40,0.85)';
function drawRobots(P) {
  const virtual = new Path2D(), wheels = new Path2D();
  const shown = [], labels = [];
  let outlines = 0, wheeled = 0;
  for (const r of run.poses.robots) {
    const body = bodyOf(r.id);
    const scale = P.affine ? P.affine.ax : P.scaleAt(r.x_m, r.y_m);
    const [u, v] = P.project(r.x_m, r.y_m);
    const radius = Math.max(3, body.radius_m * scale);
    if (!P.onCanvas(u + 120, v, radius + 130)) continue; // nor its label (right of it) on the canvas
    const d = bodyOnCanvas(body, r, P.project, scale);
    if (d.outline) ++outlines;
    if (d.wheels) {
      ++wheeled;
      for (const w of d.wheels) addPolygon(wheels, w);
    }
    if (!r.real) {
      addBody(virtual, d);
      virtual.moveTo(u, v); virtual.lineTo(d.heading[0], d.heading[1]);
    }
    shown.push([r, d]);
    if (overlays.labels) {
      labels.push([`${r.id} ${r.behaviour}${r.real && r.health && r.health !== 'ok' ? ' [' + r.health + ']' : ''}`, u + d.radius_px + 3, v - d.radius_px - 2]);
    }
  }
  ctx.fillStyle = WHEEL_CSS; ctx.fill(wheels);
  ctx.lineWidth = 2;
  for (const [r, d] of shown) {
    if (r.real) {
      // A real robot is where the camera says: blue, faint and dashed when unseen.
      ctx.strokeStyle = r.seen ? '#2456c7' : 'rgba(36,86,199,0.4)';
      ctx.setLineDash(r.seen ? [] : [4, 3]);
      const p = new Path2D();
      addBody(p, d);
      ctx.stroke(p);
      ctx.setLineDash([]);
      ctx.beginPath(); ctx.moveTo(d.centre[0], d.centre[1]); ctx.lineTo(d.heading[0], d.heading[1]); ctx.stroke();
    }
    if (driving.robot === r.id) { ctx.strokeStyle = '#e0a800'; ctx.beginPath(); ctx.arc(d.centre[0], d.centre[1], d.radius_px + 5, 0, 2 * Math.PI); ctx.stroke(); }
  }
  ctx.strokeStyle = '#d22828'; ctx.stroke(virtual);
  window.rilbed.stats.outlines = outlines; window.rilbed.stats.wheels = wheeled;
  // Many robots on the canvas: their labels only when the zoom spaces them enough to be
  // read (a label's room, LABEL_SPACING_PX, per robot on the canvas), else none.
  if (labels.length > MANY_LABELS && Math.sqrt((P.width * P.height) / labels.length) < LABEL_SPACING_PX) return;
  ctx.fillStyle = '#111'; ctx.font = '12px system-ui';
  for (const [text, x, y] of labels) ctx.fillText(text, x, y);
}

// A robot's body (body.js's bodyOnCanvas) onto `path`: its outline, or its disc.
function addBody(path, d) {
  if (d.outline) { addPolygon(path, d.outline); return; }
  const [u, v] = d.centre;
  path.moveTo(u + d.radius_px, v); path.arc(u, v, d.radius_px, 0, 2 * Math.PI);
}
function addPolygon(path, points) {
  points.forEach(([u, v], i) => { if (i) path.lineTo(u, v); else path.moveTo(u, v); });
  path.closePath();
}

// The shapes the sensor models drew (each robot's marks from its latest sensors message, so
// a message without marks clears them), moved to the robot's latest pose. One path per
// colour, stroked once: a thousand robots' marks are a few calls. A circle keeps at least a
// pixel's radius, so that millimetre marks stay visible without zoom. Returns how many.
const MARK_MIN_RADIUS_PX = 1;
function drawMarks(P) {
  const paths = new Map(); // CSS colour -> Path2D
  const path = (css) => { let p = paths.get(css); if (!p) paths.set(css, (p = new Path2D())); return p; };
  let n = 0;
  for (const r of run.poses.robots) {
    const marks = run.sensors.get(r.id)?.marks;
    if (!marks?.length) continue;
    const scale = P.affine ? P.affine.ax : P.scaleAt(r.x_m, r.y_m);
    for (const m of marksInField(marks, r)) {
      const [u, v] = P.project(m.x_m, m.y_m);
      if (m.shape === 'circle') {
        const radius = Math.max(MARK_MIN_RADIUS_PX, m.radius_m * scale);
        if (!P.onCanvas(u, v, radius + 2)) continue;
        const p = path(m.css);
        p.moveTo(u + radius, v); p.arc(u, v, radius, 0, 2 * Math.PI);
      } else { // not culled: a line may cross the canvas from ends off it
        const p = path(m.css);
        p.moveTo(u, v); p.lineTo(...P.project(m.x2_m, m.y2_m));
      }
      ++n;
    }
  }
  ctx.lineWidth = 1;
  for (const [css, p] of paths) { ctx.strokeStyle = css; ctx.stroke(p); }
  return n;
}

function drawDetections(P) {
  ctx.strokeStyle = '#00a3c4'; ctx.lineWidth = 1.5;
  for (const d of run.detections.detections) {
    const [u, v] = P.project(d.x_m, d.y_m);
    const r = Math.max(4, 0.03 * P.scaleAt(d.x_m, d.y_m));
    ctx.beginPath(); ctx.moveTo(u - r, v); ctx.lineTo(u + r, v); ctx.moveTo(u, v - r); ctx.lineTo(u, v + r); ctx.stroke();
    const [hu, hv] = P.project(d.x_m + 0.04 * Math.cos(d.theta_rad), d.y_m + 0.04 * Math.sin(d.theta_rad));
    ctx.beginPath(); ctx.moveTo(u, v); ctx.lineTo(hu, hv); ctx.stroke();
  }
}

// Where each IR ray leaves a body (its reach along the ray), worked out once a body.
const irRims = new WeakMap();
function irRim(body) {
  let rim = irRims.get(body);
  if (!rim) irRims.set(body, (rim = IR_ANGLES_RAD.map((a) => reachAlong(body, a))));
  return rim;
}

function drawSensors(P) {
  const layouts = new Map((run.world?.robots || []).map((r) => [r.id, r.sensors]));
  const idleIr = new Path2D(); // the IR rays that see nothing: one stroke for them all, last
  for (const r of run.poses.robots) {
    const s = run.sensors.get(r.id);
    if (!s) continue;
    const layout = layouts.get(r.id) || {};
    // Not drawn when none of its sensors reaches the canvas (an ultrasonic cone may reach metres).
    const [ru, rv] = P.project(r.x_m, r.y_m);
    let reach = 0.3;
    for (const g of layout.ranges || []) reach = Math.max(reach, g.max_m || 0);
    if (!P.onCanvas(ru, rv, reach * (P.affine ? P.affine.ax : P.scaleAt(r.x_m, r.y_m)) + 30)) continue;
    const c = Math.cos(r.theta_rad), sn = Math.sin(r.theta_rad);
    const at = (fx, fy) => [r.x_m + c * fx - sn * fy, r.y_m + sn * fx + c * fy]; // robot frame to field
    if (overlays.ir && s.proximity?.length === 8) {
      const reach = layout.ir_range_m || IR_RANGE_M;
      const rim = irRim(bodyOf(r.id)), A = P.affine;
      for (let i = 0; i < 8; ++i) {
        const value = s.proximity[i];
        // The ray from the rim (where it leaves the body) outwards, in the field: the robot
        // frame's (cos a, sin a) turned by theta.
        const dx = c * IR_COS[i] - sn * IR_SIN[i], dy = sn * IR_COS[i] + c * IR_SIN[i];
        const r0 = rim[i], r1 = r0 + reach;
        const x0 = r.x_m + r0 * dx, y0 = r.y_m + r0 * dy, x1 = r.x_m + r1 * dx, y1 = r.y_m + r1 * dy;
        if (value > 0) {
          ctx.strokeStyle = `rgba(230,120,0,${0.3 + 0.7 * Math.min(1, value / 1023)})`; ctx.lineWidth = 2;
          polyline(P, [[x0, y0], [x1, y1]], false); ctx.stroke();
        } else if (A) {
          idleIr.moveTo(A.ax * x0 + A.bx, A.ay * y0 + A.by); idleIr.lineTo(A.ax * x1 + A.bx, A.ay * y1 + A.by);
        } else {
          idleIr.moveTo(...P.project(x0, y0)); idleIr.lineTo(...P.project(x1, y1));
        }
      }
    }
    if (overlays.ranges && s.range_m?.length) {
      s.range_m.forEach((d, i) => {
        const g = layout.ranges?.[i];
        if (!g) return;
        const half = g.opening_rad / 2;
        const reach = s.range_hit[i] ? d : g.max_m;
        const pts = [at(0, 0)];
        for (let k = 0; k <= 8; ++k) { const a = g.mount_rad - half + (k / 8) * 2 * half; pts.push(at(reach * Math.cos(a), reach * Math.sin(a))); }
        ctx.fillStyle = s.range_hit[i] ? 'rgba(140,60,200,0.18)' : 'rgba(140,60,200,0.06)';
        ctx.strokeStyle = 'rgba(140,60,200,0.5)'; ctx.lineWidth = 1;
        polyline(P, pts, true); ctx.fill(); ctx.stroke();
      });
    }
    if (overlays.beacons && s.beacon_id?.length) {
      s.beacon_id.forEach((id, i) => {
        const a = s.beacon_bearing_rad[i];
        ctx.strokeStyle = 'rgba(224,168,0,0.9)'; ctx.lineWidth = 1.5; ctx.setLineDash([5, 4]);
        polyline(P, [at(0, 0), at(0.25 * Math.cos(a), 0.25 * Math.sin(a))], false); ctx.stroke(); ctx.setLineDash([]);
        const [u, v] = P.project(...at(0.27 * Math.cos(a), 0.27 * Math.sin(a)));
        ctx.fillStyle = '#8a6800'; ctx.font = '10px system-ui'; ctx.fillText(`B${id}`, u, v);
      });
    }
    if (overlays.tracks && s.track?.length) {
      // Each element's floor segments (where its light falls), filled when it sees tape.
      s.track.forEach((value, i) => {
        const points = layout.tracks?.[i];
        if (!points?.length) return;
        ctx.fillStyle = value > 0 ? 'rgba(30,125,50,0.85)' : 'rgba(30,125,50,0.25)';
        const r = Math.max(1.5, 0.002 * P.scaleAt(r0x(), r0y()));
        for (const p of points) {
          const [u, v] = P.project(...at(p.x_m, p.y_m));
          ctx.beginPath(); ctx.arc(u, v, r, 0, 2 * Math.PI); ctx.fill();
        }
      });
    }
  }
  ctx.strokeStyle = 'rgba(120,120,120,0.25)'; ctx.lineWidth = 1; ctx.stroke(idleIr);
  function r0x() { return run.world ? run.world.width_m / 2 : 0; }
  function r0y() { return run.world ? run.world.height_m / 2 : 0; }
}

new ResizeObserver(requestDraw).observe(canvas);

// ------------------------------------------------------------------ plots
let plotsDirty = false;
let lastPlot = 0, plotTimer = null;
const COLORS = ['#d22828', '#2456c7', '#1e7d32', '#b26a00', '#7b1fa2', '#00838f', '#c2185b', '#5d4037', '#455a64', '#9e9d24'];

function plotCanvas(id) { return prepareCanvas($(id)); }

function drawPlots() {
  const now = performance.now();
  if (now - lastPlot < 500) { // twice a second is plenty; one redraw waits for the next
    plotTimer ||= setTimeout(() => { plotTimer = null; requestDraw(); }, 500 - (now - lastPlot));
    return;
  }
  lastPlot = now; plotsDirty = false;
  // Formation: distance to the robot ahead, followers only.
  {
    const [g, w, h] = plotCanvas('formation-plot');
    let tMax = 1, dMax = 0.3, followed = false;
    for (const s of run.formation.values()) {
      for (const [t, d] of s) { tMax = Math.max(tMax, t); if (d !== null) { dMax = Math.max(dMax, d); followed = true; } }
    }
    const L = 36, B = 20;
    axes(g, w, h, L, B, `${tMax.toFixed(0)} s`, `${dMax.toFixed(2)} m`);
    const compact = run.formation.size > LEGEND_ROBOTS; // a label each would not fit
    let k = 0;
    for (const [id, s] of run.formation) {
      g.strokeStyle = COLORS[k++ % COLORS.length]; g.lineWidth = 1.2; g.beginPath();
      let pen = plotPen(g);
      for (const [t, d] of s) {
        if (d === null) { pen = plotPen(g); continue; }
        pen(L + (t / tMax) * (w - L - 4), h - B - (d / dMax) * (h - B - 4));
      }
      g.stroke();
      const x = w - 4 - 14 * (run.formation.size - k + 1);
      if (!compact && x > -30) { g.fillStyle = g.strokeStyle; g.fillText(String(id), x, 12); } // not the legend off the plot
    }
    if (compact) {
      const n = `${run.formation.size} followers`;
      g.fillStyle = '#666'; g.fillText(n, w - 8 - g.measureText(n).width, 12);
    }
    if (!followed && run.poses) { // say why the plot is empty
      const n = 'no robot has followed another yet';
      g.fillStyle = '#888'; g.font = '12px system-ui'; g.fillText(n, (w - g.measureText(n).width) / 2, h / 2);
    }
  }
  drawTrajectories();
}

// Trajectories: every robot's path over the field. The paths are drawn onto an offscreen
// canvas a piece at a time (what came since the last plot), and drawn anew only when the
// plot's size or scale changes or the history starts again; the labels go on top each time.
const trajectoryPlot = { key: '', canvas: document.createElement('canvas'), scale: 0, last: new Map() };
function drawTrajectories() {
  const [g, w, h] = plotCanvas('trajectory-plot');
  if (w <= 0 || h <= 0) return; // not shown
  const dpr = window.devicePixelRatio || 1;
  const fw = run.world?.width_m || 1, fh = run.world?.height_m || 1;
  const s = Math.min((w - 8) / fw, (h - 8) / fh), ox = (w - s * fw) / 2, oy = (h + s * fh) / 2;
  const T = trajectoryPlot, off = T.canvas;
  const key = `${w} ${h} ${dpr} ${fw} ${fh}`;
  const o = off.getContext('2d');
  if (T.key !== key) {
    T.key = key; T.scale = s; T.last.clear();
    off.width = Math.round(w * dpr); off.height = Math.round(h * dpr);
    o.setTransform(dpr, 0, 0, dpr, 0, 0); o.clearRect(0, 0, w, h);
    o.strokeStyle = '#1a9e2a'; o.lineWidth = 1; o.strokeRect(ox, oy - s * fh, s * fw, s * fh);
  }
  let k = 0;
  o.lineWidth = 1.2;
  for (const [id, pts] of run.history) {
    o.strokeStyle = COLORS[k++ % COLORS.length];
    const last = T.last.get(id); // [t, u, v] of the last point drawn
    let i = pts.length;
    if (last) while (i > 0 && pts[i - 1][0] > last[0]) --i; else i = 0;
    if (i === pts.length) continue;
    o.beginPath();
    const pen = plotPen(o);
    if (last) pen(last[1], last[2]);
    let u = 0, v = 0;
    for (; i < pts.length; ++i) { u = ox + s * pts[i][1]; v = oy - s * pts[i][2]; pen(u, v); }
    o.stroke();
    T.last.set(id, [pts[pts.length - 1][0], u, v]);
  }
  g.drawImage(off, 0, 0, w, h);
  if (run.history.size > LEGEND_ROBOTS) { // a label at each path's end would cover the plot
    const n = `${run.history.size} robots`;
    g.fillStyle = '#666'; g.font = '10px system-ui'; g.fillText(n, w - 8 - g.measureText(n).width, 12);
    return;
  }
  k = 0;
  for (const [id, pts] of run.history) {
    g.fillStyle = COLORS[k++ % COLORS.length];
    const last = pts[pts.length - 1];
    if (last) g.fillText(String(id), ox + s * last[1] + 3, oy - s * last[2] - 3);
  }
}

// A polyline's pen on `g` (moveTo, then lineTo) that leaves out each point within half a pixel
// of the last one drawn: a thousand robots' minutes of samples are millions of points, most
// under a pixel apart, which take seconds to stroke. The line stays within half a pixel of
// every point.
function plotPen(g) {
  let first = true, lx = 0, ly = 0;
  return (x, y) => {
    if (!first && Math.abs(x - lx) < 0.5 && Math.abs(y - ly) < 0.5) return;
    if (first) g.moveTo(x, y); else g.lineTo(x, y);
    first = false; lx = x; ly = y;
  };
}

function axes(g, w, h, L, B, xLabel, yLabel) {
  g.strokeStyle = '#999'; g.lineWidth = 1;
  g.beginPath(); g.moveTo(L, 4); g.lineTo(L, h - B); g.lineTo(w - 4, h - B); g.stroke();
  g.fillStyle = '#666'; g.font = '10px system-ui';
  g.fillText('0', L - 10, h - B + 12); g.fillText(xLabel, w - 30, h - B + 12); g.fillText(yLabel, 2, 12);
}
