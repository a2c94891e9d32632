#!/usr/bin/env node
// How fast the live view draws a large run: a benchmark, not a test (it checks nothing and
// always exits 0 unless something breaks). The goal is 30 frames/s or more with 1,000
// robots and their trails.
//
//   node web/tests/draw_bench.js [--seconds S] [--warmup S] [--dpr R] [--robots 100,1000] [--web DIR]
//
// --web DIR serves the page from DIR instead of web/ (a copy, to compare a change).
//
// It runs the real page (web/index.html, app.js, foxglove.js, canvas.js, editor.js, the
// style sheets) in Debian's headless Chromium, driven by playwright-core, against a
// stand-in for `rilbed run --gui` written here in Node: the same HTTP rules (the token in
// the page's query, then the rilbed_token_PORT cookie for its files; the token in the
// query of /ws; Origin; the foxglove.websocket.v1 subprotocol), the same serverInfo (with
// the parameters capabilities; a run without a camera has no parameters), the same twelve
// channels with the same topics, schemas and ids (src/gui_web/run_channels.cpp) and the same
// JSON payloads, published in the order and at the rate the run publishes them
// (src/agents/simulation.cpp): every control step (100 ms, 10 Hz) the world (on a new
// second), the behaviour events, the poses, the scene, the wheels, the sensors (the step
// reports only if someone subscribed) and the status (on a new second), stamped
// t = step * 0.1 s - 1 us as the run stamps them; latched channels replayed to a subscriber.
//
// The world: a 20 m x 20 m walled field with four boxes, N virtual Kheperas (an IR ring
// of 5 cm, like scenarios/wander.yaml's) driving at 0.08-0.12 m/s along smooth random
// paths (an Ornstein-Uhlenbeck turn rate), turning away from the walls ("avoid"), else
// "cruise". Their IR readings see the walls.
//
// For each robot count: a fresh server and page; the run is first fast-forwarded 40 s
// (400 steps, as fast as the page takes them, trails hidden meanwhile) so that every trail
// is full (the page keeps 400 points), then runs in real time. Then, trails on and off
// (the page's checkbox; the mouse then rests on the live view), in two ways:
//   live       the page as it is when watched: it draws when a message comes (10 Hz poses
//              and sensors, 1 Hz world and status, events), at most once a frame;
//   zooming    the view zoomed in and out by 0.15% every frame as well (a wheel event on it
//              each frame), so that every frame is drawn anew, as while someone zooms or
//              drags the view: the most the page can draw (vsync is 60 Hz, the ceiling).
//              The trails are then the layer laid before the view moved, drawn moved
//              and scaled (app.js lays it anew once the view rests 150 ms), as for anyone
//              zooming or dragging.
// Each: a warm-up, then a measured window. Frames are the page's own count,
// window.rilbed.stats.frames (one per draw()); the frame intervals and draw()'s own
// JavaScript time come from a wrapper around requestAnimationFrame that times the
// callbacks named `draw` (installed before the page's scripts; app.js is unchanged).
// A frame interval includes everything the main thread did between two draws: the
// messages (JSON parsing, the trails, the agent table), draw() itself and the canvas's
// rasterization (software in headless Chromium).
//
// Prints a Markdown table and how it was measured; saves one screenshot of the page with
// the most robots (trails on) to build/web-artifacts/draw_bench_N.png (N = 1000 by default).
// It takes about 8 minutes on a 2-core machine, most of it the 1,000-robot fast-forward.
'use strict';

const crypto = require('node:crypto');
const fs = require('node:fs');
const http = require('node:http');
const os = require('node:os');
const path = require('node:path');

const NAME = 'draw_bench';
const CHROMIUM = '/usr/bin/chromium';
const DEFAULT_WEB_ROOT = path.resolve(__dirname, '..');
let WEB_ROOT = DEFAULT_WEB_ROOT; // --web DIR: another copy of the page
const REPO = path.resolve(DEFAULT_WEB_ROOT, '..');
const ARTIFACTS = path.join(REPO, 'build', 'web-artifacts');
const VIEWPORT = { width: 1280, height: 900 };
const STEP_US = 100_000;            // the control period (scenario.hpp: control_period_us)
const PREFILL_STEPS = 400;          // 40 s: every trail full (app.js TRAIL_POINTS)
const FIELD_M = 20;
const MAX_QUEUED_BYTES = 8 << 20;   // WebServerConfig::max_queued_bytes
const MAX_MESSAGE_BYTES = 1 << 20;  // WebServerConfig::max_message_bytes
const SUBPROTOCOL = 'foxglove.websocket.v1';

// ---------------------------------------------------------------- arguments
function parseArgs(argv) {
  const a = { seconds: 10, warmup: 3, dpr: 1, robots: [100, 1000] };
  for (let i = 0; i < argv.length; ++i) {
    const next = () => {
      if (i + 1 >= argv.length) usage(`${argv[i]} needs a value`);
      return argv[++i];
    };
    switch (argv[i]) {
      case '--seconds': a.seconds = Number(next()); break;
      case '--warmup': a.warmup = Number(next()); break;
      case '--dpr': a.dpr = Number(next()); break;
      case '--robots': a.robots = next().split(',').map(Number); break;
      case '--web': WEB_ROOT = path.resolve(next()); break;
      case '-h': case '--help': usage(); break;
      default: usage(`unknown argument ${argv[i]}`);
    }
  }
  if (!(a.seconds > 0) || !(a.warmup >= 0) || !(a.dpr > 0) || !a.robots.every((n) => Number.isInteger(n) && n > 0)) {
    usage('--seconds and --dpr must be > 0, --warmup >= 0, --robots positive integers');
  }
  return a;
}
function usage(problem) {
  if (problem) console.error(`${NAME}: ${problem}`);
  console.error('usage: node web/tests/draw_bench.js [--seconds S (10)] [--warmup S (3)] [--dpr R (1)] [--robots 100,1000] [--web DIR (web/)]');
  process.exit(problem ? 2 : 0);
}

function requirePackages() {
  const modules = path.join(__dirname, 'node_modules');
  const missing = `${modules} is missing or incomplete: run npm ci in web/tests (or ./run test)`;
  if (!fs.existsSync(modules)) throw new Error(missing);
  if (!fs.existsSync(CHROMIUM)) throw new Error(`no ${CHROMIUM}: ./run test installs Debian's chromium`);
  try {
    return { playwright: require('playwright-core'), WebSocketServer: require('ws').WebSocketServer };
  } catch (e) {
    throw new Error(`${missing} (${e.message})`, { cause: e });
  }
}

// ---------------------------------------------------------------- the run's channels
// JSON Schemas as run_channels.cpp builds them (nlohmann::json objects: keys sorted).
const num = { type: 'number' }, int = { type: 'integer' }, str = { type: 'string' }, bool = { type: 'boolean' };
const arrayOf = (items) => ({ items, type: 'array' });
const objectOf = (properties) => ({ properties: sortKeys(properties), type: 'object' });
const objectSchema = (title, properties) => dump({ properties: sortKeys(properties), title, type: 'object' });
function sortKeys(o) {
  if (Array.isArray(o)) return o.map(sortKeys);
  if (o === null || typeof o !== 'object') return o;
  const out = {};
  for (const k of Object.keys(o).sort()) out[k] = sortKeys(o[k]);
  return out;
}
// nlohmann's dump(): keys in sorted order, compact.
const dump = (o) => JSON.stringify(sortKeys(o));

function channels() {
  const robotPose = objectOf({ id: int, real: bool, seen: bool, x_m: num, y_m: num, theta_rad: num, behaviour: str, health: str });
  const polyline = arrayOf(objectOf({ x_m: num, y_m: num }));
  const time = objectOf({ sec: int, nsec: int });
  const vec3 = objectOf({ x: num, y: num, z: num });
  const quat = objectOf({ x: num, y: num, z: num, w: num });
  const poseS = objectOf({ position: vec3, orientation: quat });
  const colorS = objectOf({ r: num, g: num, b: num, a: num });
  const entity = objectOf({
    timestamp: time, frame_id: str, id: str, lifetime: time, frame_locked: bool,
    cylinders: arrayOf(objectOf({ pose: poseS, size: vec3, bottom_scale: num, top_scale: num, color: colorS })),
    texts: arrayOf(objectOf({ pose: poseS, billboard: bool, font_size: num, scale_invariant: bool, color: colorS, text: str })),
    lines: arrayOf(objectOf({ type: int, pose: poseS, thickness: num, scale_invariant: bool, points: arrayOf(vec3), color: colorS,
      colors: arrayOf(colorS), indices: arrayOf(int) })),
    arrows: arrayOf(objectOf({ pose: poseS, shaft_length: num, shaft_diameter: num, head_length: num, head_diameter: num, color: colorS })),
  });
  const list = [
    ['/rilbed/world', 'rilbed.world', objectSchema('rilbed.world', {
      t_s: num, scenario: str, width_m: num, height_m: num, walls: bool, obstacles: arrayOf(polyline),
      tracks: arrayOf(objectOf({ points: polyline, width_m: num })), beacons: polyline,
      robots: arrayOf(objectOf({ id: int, real: bool, sensors: objectOf({ ir_range_m: num,
        ranges: arrayOf(objectOf({ mount_rad: num, opening_rad: num, max_m: num })), beacon_finder: bool, beacon_fov_rad: num,
        tracks: arrayOf(polyline) }) })) }), true],
    ['/rilbed/status', 'rilbed.status', objectSchema('rilbed.status', {
      t_s: num, wall_s: num, scenario: str, seed: int, mode: str, realtime: bool, rt_factor: num, state: str, ended_by: str,
      robots: int, real_robots: int, formed: bool, formation_time_s: num, collisions: int, loop_latency_ms: num,
      camera_fps: num, frames: int }), true],
    ['/rilbed/poses', 'rilbed.poses', objectSchema('rilbed.poses', { t_s: num, robots: arrayOf(robotPose) }), true],
    ['/rilbed/wheels', 'rilbed.wheels', objectSchema('rilbed.wheels', { t_s: num,
      robots: arrayOf(objectOf({ id: int, left_units: int, right_units: int })) }), false],
    ['/rilbed/sensors', 'rilbed.sensors', objectSchema('rilbed.sensors', { t_s: num,
      robots: arrayOf(objectOf({ id: int, proximity: arrayOf(int), range_m: arrayOf(num), range_hit: arrayOf(bool),
        beacon_id: arrayOf(int), beacon_bearing_rad: arrayOf(num), track: arrayOf(int) })) }), false],
    ['/rilbed/detections', 'rilbed.detections', objectSchema('rilbed.detections', { t_s: num, frame: int, process_ms: num,
      detections: arrayOf(objectOf({ id: int, u_px: num, v_px: num, heading_deg: num, score: num, diameter_px: num, x_m: num,
        y_m: num, theta_rad: num })) }), false],
    ['/rilbed/events', 'rilbed.event', objectSchema('rilbed.event', { t_s: num, kind: str, id: int, other: int, detail: str }), false],
    ['/rilbed/summary', 'rilbed.summary', objectSchema('rilbed.summary', {}), false],
    ['/rilbed/scene', 'foxglove.SceneUpdate', objectSchema('foxglove.SceneUpdate', {
      deletions: arrayOf(objectOf({ timestamp: time, type: int, id: str })), entities: arrayOf(entity) }), true],
    ['/rilbed/camera', 'foxglove.CompressedImage', objectSchema('foxglove.CompressedImage', { timestamp: time, frame_id: str,
      data: { contentEncoding: 'base64', type: 'string' }, format: str }), false],
    ['/rilbed/camera_calibration', 'rilbed.camera', objectSchema('rilbed.camera', { t_s: num, width_px: int, height_px: int,
      image_to_field: arrayOf(num), field_to_image: arrayOf(num), lens_distortion: bool, source: str }), true],
    ['/rilbed/console_reply', 'rilbed.console_reply', objectSchema('rilbed.console_reply', { t_s: num, accepted: bool,
      reason: str, client: str }), false],
  ];
  return list.map(([topic, schemaName, schema, latched], i) =>
    ({ id: i + 1, topic, encoding: 'json', schemaName, schema, schemaEncoding: 'jsonschema', latched }));
}

// ---------------------------------------------------------------- the stand-in run
function mulberry32(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

const IR_ANGLES = [90, 45, 10, -10, -45, -90, -170, 170].map((d) => (d * Math.PI) / 180);
const RADIUS_M = 0.0275, IR_RANGE_M = 0.05, WHEEL_BASE_M = 0.0885, SPEED_PER_UNIT_MPS = 0.00678;

class StandInRun {
  constructor(robots, seed = 1, fieldM = FIELD_M) {
    this.n = robots;
    this.seed = seed;
    this.rand = mulberry32(seed);
    const gauss = () => Math.sqrt(-2 * Math.log(1 - this.rand())) * Math.cos(2 * Math.PI * this.rand());
    this.gauss = gauss;
    this.width = fieldM; this.height = fieldM;
    this.scenario = `draw_bench_${robots}`;
    // Four boxes, drawn only (the robots drive through them: it changes nothing drawn).
    const box = (x, y, w, h) => [[x, y], [x + w, y], [x + w, y + h], [x, y + h]].map(([a, b]) => [(a * fieldM) / 20, (b * fieldM) / 20]);
    this.obstacles = [box(4, 4, 1.5, 1), box(14, 4, 1, 2), box(4, 14, 2, 1), box(13, 13, 1.2, 1.2)];
    this.robots = [];
    for (let i = 0; i < robots; ++i) {
      this.robots.push({ id: i + 1, x: 0.3 + this.rand() * (this.width - 0.6), y: 0.3 + this.rand() * (this.height - 0.6),
        theta: (this.rand() * 2 - 1) * Math.PI, v: 0.08 + 0.04 * this.rand(), w: 0, behaviour: 'cruise',
        prox: new Array(8).fill(0) });
    }
    this.step = 0;
    this.wallStart = process.hrtime.bigint();
  }

  tUs() { return this.step * STEP_US - 1; } // the control step just taken (simulation.cpp: t_us_ - 1)

  // One control step of 0.1 s; returns the behaviour changes [id, from, to].
  advance() {
    this.step += 1;
    const dt = STEP_US * 1e-6, tau = 2.0, sigma = 0.8, margin = 0.25;
    const changes = [];
    for (const r of this.robots) {
      const nearWall = Math.min(r.x, r.y, this.width - r.x, this.height - r.y) < margin;
      let behaviour = 'cruise';
      if (nearWall) {
        // Turn toward the field's centre, as a Braitenberg wanderer turns from a wall.
        const want = Math.atan2(this.height / 2 - r.y, this.width / 2 - r.x);
        const off = Math.atan2(Math.sin(want - r.theta), Math.cos(want - r.theta));
        if (Math.abs(off) > 0.3) { r.w = Math.sign(off) * 1.5; behaviour = 'avoid'; }
      }
      if (behaviour === 'cruise') r.w += (-r.w / tau) * dt + sigma * Math.sqrt(dt) * this.gauss();
      r.theta = Math.atan2(Math.sin(r.theta + r.w * dt), Math.cos(r.theta + r.w * dt));
      r.x = Math.min(this.width - RADIUS_M, Math.max(RADIUS_M, r.x + r.v * Math.cos(r.theta) * dt));
      r.y = Math.min(this.height - RADIUS_M, Math.max(RADIUS_M, r.y + r.v * Math.sin(r.theta) * dt));
      // IR: the walls within 5 cm of the robot's rim along each sensor's direction.
      for (let i = 0; i < 8; ++i) {
        const a = r.theta + IR_ANGLES[i], dx = Math.cos(a), dy = Math.sin(a);
        const x0 = r.x + RADIUS_M * dx, y0 = r.y + RADIUS_M * dy;
        let d = Infinity;
        if (dx > 1e-9) d = Math.min(d, (this.width - x0) / dx);
        if (dx < -1e-9) d = Math.min(d, -x0 / dx);
        if (dy > 1e-9) d = Math.min(d, (this.height - y0) / dy);
        if (dy < -1e-9) d = Math.min(d, -y0 / dy);
        r.prox[i] = d < IR_RANGE_M ? Math.round(1023 * (1 - Math.max(0, d) / IR_RANGE_M)) : 0;
      }
      if (behaviour !== r.behaviour) changes.push([r.id, r.behaviour, behaviour]);
      r.behaviour = behaviour;
    }
    return changes;
  }

  // The payloads, as run_channels.cpp writes them (keys in nlohmann's sorted order).
  worldJson() {
    const t_s = this.tUs() * 1e-6;
    const sensors = { beacon_finder: false, beacon_fov_rad: 0.0, ir_range_m: IR_RANGE_M, ranges: [], tracks: [] };
    return JSON.stringify({
      beacons: [], height_m: this.height,
      obstacles: this.obstacles.map((o) => o.map(([x, y]) => ({ x_m: x, y_m: y }))),
      robots: this.robots.map((r) => ({ id: r.id, real: false, sensors })),
      scenario: this.scenario, t_s, tracks: [], walls: true, width_m: this.width,
    });
  }
  posesJson() {
    return JSON.stringify({ robots: this.robots.map((r) => ({ behaviour: r.behaviour, health: 'ok', id: r.id, real: false,
      seen: true, theta_rad: r.theta, x_m: r.x, y_m: r.y })), t_s: this.tUs() * 1e-6 });
  }
  wheelsJson() {
    const units = (mps) => Math.max(-127, Math.min(127, Math.round(mps / SPEED_PER_UNIT_MPS)));
    return JSON.stringify({ robots: this.robots.map((r) => ({ id: r.id, left_units: units(r.v - (r.w * WHEEL_BASE_M) / 2),
      right_units: units(r.v + (r.w * WHEEL_BASE_M) / 2) })), t_s: this.tUs() * 1e-6 });
  }
  sensorsJson() {
    return JSON.stringify({ robots: this.robots.map((r) => ({ beacon_bearing_rad: [], beacon_id: [], id: r.id,
      proximity: r.prox, range_hit: [], range_m: [], track: [] })), t_s: this.tUs() * 1e-6 });
  }
  statusJson() {
    return dump({ camera_fps: 0.0, collisions: 0, ended_by: '', formation_time_s: null, formed: false, frames: 0,
      loop_latency_ms: 0.4, mode: 'distributed', real_robots: 0, realtime: true, robots: this.n, rt_factor: 1.0,
      scenario: this.scenario, seed: this.seed, state: 'running', t_s: this.tUs() * 1e-6,
      wall_s: Number(process.hrtime.bigint() - this.wallStart) * 1e-9 });
  }
  eventJson([id, from, to]) {
    return dump({ detail: `${from} -> ${to}`, id, kind: 'behaviour', other: 0, t_s: this.tUs() * 1e-6 });
  }
  // scene_json: a field entity and one per robot (only built when someone subscribed).
  sceneJson() {
    const t = this.tUs();
    const time = { nsec: (t % 1_000_000) * 1000, sec: Math.floor(t / 1_000_000) };
    const point = (x, y, z = 0) => ({ x, y, z });
    const pose = (x, y, z, yaw) => ({ orientation: { w: Math.cos(yaw / 2), x: 0, y: 0, z: Math.sin(yaw / 2) }, position: point(x, y, z) });
    const color = (r, g, b, a = 1) => ({ a, b, g, r });
    const entity = (id) => ({ arrows: [], cubes: [], cylinders: [], frame_id: 'field', frame_locked: false, id,
      lifetime: { nsec: 0, sec: 0 }, lines: [], metadata: [], models: [], spheres: [], texts: [], timestamp: time, triangles: [] });
    const line = (pts, loop, thickness, c) => ({ color: c, colors: [], indices: [], points: pts.map(([x, y]) => point(x, y)),
      pose: pose(0, 0, 0, 0), scale_invariant: false, thickness, type: loop ? 1 : 0 });
    const field = entity('field');
    field.lines.push(line([[0, 0], [this.width, 0], [this.width, this.height], [0, this.height]], true, 0.01, color(0.1, 0.7, 0.1)));
    for (const o of this.obstacles) field.lines.push(line(o, true, 0.01, color(0.3, 0.3, 0.3)));
    const entities = [field];
    for (const r of this.robots) {
      const e = entity(`robot ${r.id}`);
      e.cylinders.push({ bottom_scale: 1.0, color: color(0.9, 0.15, 0.15, 0.8), pose: pose(r.x, r.y, 0.01, r.theta),
        size: point(0.055, 0.055, 0.02), top_scale: 1.0 });
      e.arrows.push({ color: color(0, 0, 0), head_diameter: 0.014, head_length: 0.012, pose: pose(r.x, r.y, 0.025, r.theta),
        shaft_diameter: 0.006, shaft_length: 0.03 });
      e.texts.push({ billboard: true, color: color(0, 0, 0), font_size: 12.0, pose: pose(r.x, r.y, 0.06, 0), scale_invariant: true,
        text: `${r.id} ${r.behaviour}` });
      entities.push(e);
    }
    return JSON.stringify({ deletions: [], entities });
  }
}

// ---------------------------------------------------------------- the server
// web_server.cpp's rules, in Node: the page's files for the token in the query (which
// sets the cookie rilbed_token_PORT) or the cookie; the WebSocket at /ws for the token in
// the query only, an allowed Origin and the foxglove.websocket.v1 subprotocol.
class StandInServer {
  constructor(WebSocketServer, run) {
    this.run = run;
    this.token = crypto.randomBytes(16).toString('hex');
    this.channels = channels();
    this.byTopic = new Map(this.channels.map((c) => [c.topic, c]));
    this.latest = new Map(); // latched channel id -> [tNs, payload Buffer]
    this.sessions = new Set();
    this.counts = { requests: 0, refused: 0, sent: 0, dropped: 0, bytes: 0, posesSent: 0 };
    this.wss = new WebSocketServer({ noServer: true, maxPayload: MAX_MESSAGE_BYTES, perMessageDeflate: false,
      handleProtocols: () => SUBPROTOCOL });
    this.http = http.createServer((req, res) => this.onRequest(req, res));
    this.http.on('upgrade', (req, socket, head) => this.onUpgrade(req, socket, head));
    this.timer = null;
  }

  listen() {
    return new Promise((resolve) => this.http.listen(0, '127.0.0.1', () => {
      this.port = this.http.address().port;
      resolve();
    }));
  }
  get url() { return `http://127.0.0.1:${this.port}/?token=${this.token}`; }
  cookieName() { return `rilbed_token_${this.port}`; }

  // "/ws?token=abc&x=1" -> path, token (the last token= pair, as parse_target reads it; not decoded).
  static target(t) {
    const q = t.indexOf('?');
    const out = { path: q < 0 ? t : t.slice(0, q), token: '' };
    if (q >= 0) for (const pair of t.slice(q + 1).split('&')) if (pair.startsWith('token=')) out.token = pair.slice(6);
    return out;
  }
  cookieToken(header = '') {
    for (let item of header.split(';')) {
      item = item.replace(/^ +/, '');
      if (item.startsWith(`${this.cookieName()}=`)) return item.slice(this.cookieName().length + 1);
    }
    return '';
  }
  sameSecret(a) { return a.length > 0 && a.length === this.token.length && crypto.timingSafeEqual(Buffer.from(a), Buffer.from(this.token)); }
  originAllowed(origin, host) {
    if (!origin) return true;
    if (host && origin === `http://${host}`) return true;
    return ['127.0.0.1', 'localhost', '[::1]'].some((h) => origin === `http://${h}:${this.port}`);
  }

  static head(status, type, length, extra = {}) {
    return { Server: 'rilbed', 'Content-Type': type, 'Cache-Control': 'no-store', Connection: 'close', 'Content-Length': length, ...extra };
  }
  onRequest(req, res) {
    this.counts.requests += 1;
    const t = StandInServer.target(req.url);
    const byQuery = this.sameSecret(t.token);
    const byCookie = !byQuery && this.sameSecret(this.cookieToken(req.headers.cookie));
    const respond = (status, type, body) => {
      const extra = byQuery && status === 200
        ? { 'Set-Cookie': `${this.cookieName()}=${this.token}; Path=/; HttpOnly; SameSite=Strict` } : {};
      if (status !== 200) this.counts.refused += status === 404 ? 0 : 1;
      res.writeHead(status, StandInServer.head(status, type, body.length, extra));
      res.end(req.method === 'HEAD' ? undefined : body);
    };
    if (!byQuery && !byCookie) return respond(401, 'text/plain', Buffer.from('a valid ?token= is needed\n'));
    if (req.method !== 'GET' && req.method !== 'HEAD') return respond(405, 'text/plain', Buffer.from('GET only\n'));
    const notFound = () => respond(404, 'text/plain', Buffer.from('not found\n'));
    if (t.path.includes('..') || !t.path.startsWith('/')) return notFound();
    const file = path.join(WEB_ROOT, t.path === '/' ? 'index.html' : t.path.slice(1));
    fs.readFile(file, (err, body) => {
      if (err) return notFound();
      const types = { '.html': 'text/html; charset=utf-8', '.js': 'text/javascript; charset=utf-8', '.mjs': 'text/javascript; charset=utf-8',
        '.css': 'text/css; charset=utf-8', '.json': 'application/json', '.svg': 'image/svg+xml', '.png': 'image/png' };
      respond(200, types[path.extname(file)] || 'application/octet-stream', body);
    });
  }

  onUpgrade(req, socket, head) {
    this.counts.requests += 1;
    const refuse = (status, text, why) => {
      this.counts.refused += 1;
      socket.end(`HTTP/1.1 ${status} ${text}\r\n` + Object.entries(StandInServer.head(status, 'text/plain', Buffer.byteLength(why)))
        .map(([k, v]) => `${k}: ${v}\r\n`).join('') + `\r\n${why}`);
    };
    const t = StandInServer.target(req.url);
    if (!this.sameSecret(t.token)) return refuse(401, 'Unauthorized', 'a valid ?token= is needed\n');
    if (t.path !== '/ws') return refuse(404, 'Not Found', 'the WebSocket is at /ws\n');
    if (!this.originAllowed(req.headers.origin, req.headers.host)) return refuse(403, 'Forbidden', 'Origin not allowed\n');
    const offered = (req.headers['sec-websocket-protocol'] || '').split(',').map((s) => s.trim());
    if (!offered.includes(SUBPROTOCOL)) {
      return refuse(400, 'Bad Request', `Missing expected sec-websocket-protocol header (${SUBPROTOCOL})\n`);
    }
    this.wss.handleUpgrade(req, socket, head, (ws) => this.onSession(ws));
  }

  onSession(ws) {
    const s = { ws, channelToSub: new Map(), subToChannel: new Map(), clientChannels: new Map(), lastSlow: 0 };
    this.sessions.add(s);
    const text = (o) => ws.send(JSON.stringify(o));
    const status = (level, message, id) => text(id ? { op: 'status', level, message, id } : { op: 'status', level, message });
    // The capabilities of rilbed's server with its vision-settings parameters (a run
    // without a camera has none of them: getParameters answers an empty list).
    text({ op: 'serverInfo', name: 'rilbed', capabilities: ['clientPublish', 'parameters', 'parametersSubscribe'],
      supportedEncodings: ['json'], metadata: {}, sessionId: this.token.slice(0, 8) });
    text({ op: 'advertise', channels: this.channels.map(({ latched: _latched, ...c }) => c) });
    s.status = status;
    ws.on('close', () => this.sessions.delete(s));
    ws.on('message', (data, isBinary) => {
      if (isBinary) {
        const b = Buffer.from(data);
        if (b.length < 5 || b[0] !== 1) return status(2, 'a binary message that is not a client message');
        const channel = s.clientChannels.get(b.readUInt32LE(1));
        if (!channel) return status(2, `Channel ${b.readUInt32LE(1)} is not advertised`);
        return status(2, `${NAME}: this stand-in for rilbed takes no commands (${channel.topic})`);
      }
      let m;
      try { m = JSON.parse(data.toString('utf8')); } catch (e) { return status(2, `not JSON: ${e.message}`); }
      if (m.op === 'subscribe') {
        for (const { id, channelId } of m.subscriptions || []) {
          if (!this.channels[channelId - 1]) status(1, `Channel ${channelId} is not available; ignoring subscription`);
          else if (s.subToChannel.has(id)) status(2, `Client subscription id ${id} was already used; ignoring subscription`);
          else if (s.channelToSub.has(channelId)) status(1, `Client already subscribed to channel ${channelId}; ignoring subscription`);
          else {
            s.subToChannel.set(id, channelId);
            s.channelToSub.set(channelId, id);
            const last = this.latest.get(channelId);
            if (last) this.offer(s, channelId, last[0], last[1]);
          }
        }
      } else if (m.op === 'unsubscribe') {
        for (const id of m.subscriptionIds || []) {
          const c = s.subToChannel.get(id);
          if (c === undefined) { status(1, `Client subscription id ${id} did not exist; ignoring unsubscription`); continue; }
          s.channelToSub.delete(c);
          s.subToChannel.delete(id);
        }
      } else if (m.op === 'advertise') {
        for (const c of m.channels || []) s.clientChannels.set(c.id, c);
      } else if (m.op === 'unadvertise') {
        for (const id of m.channelIds || []) s.clientChannels.delete(id);
      } else if (m.op === 'getParameters') {
        text(m.id === undefined ? { op: 'parameterValues', parameters: [] } : { op: 'parameterValues', parameters: [], id: m.id });
      } else if (m.op === 'setParameters') {
        status(2, 'vision settings refused: this run has no camera');
        text(m.id === undefined ? { op: 'parameterValues', parameters: [] } : { op: 'parameterValues', parameters: [], id: m.id });
      } else if (m.op === 'subscribeParameterUpdates' || m.op === 'unsubscribeParameterUpdates') {
        // nothing ever changes: no camera
      } else {
        status(2, `unknown op '${String(m.op).slice(0, 64)}'`);
      }
    });
  }

  subscribed(topic) {
    const id = this.byTopic.get(topic).id;
    return [...this.sessions].some((s) => s.channelToSub.has(id));
  }

  // A data message, if this client subscribed; dropped (as the server's bounded queue drops
  // the oldest) when the client has 8 MiB waiting.
  offer(s, channelId, tNs, payload) {
    const sub = s.channelToSub.get(channelId);
    if (sub === undefined) return;
    const bytes = 13 + payload.length;
    if (s.ws.bufferedAmount + bytes > MAX_QUEUED_BYTES) {
      this.counts.dropped += 1;
      const now = Date.now();
      if (now - s.lastSlow >= 1000) {
        s.lastSlow = now;
        s.status(1, 'Send buffer limit reached: this client does not keep up, older messages were dropped', 'slow');
      }
      return;
    }
    const header = Buffer.alloc(13);
    header[0] = 1;
    header.writeUInt32LE(sub, 1);
    header.writeBigUInt64LE(tNs, 5);
    s.ws.send(Buffer.concat([header, payload], bytes), { binary: true });
    this.counts.sent += 1;
    this.counts.bytes += bytes;
    if (channelId === this.byTopic.get('/rilbed/poses').id) this.counts.posesSent += 1;
  }

  publish(topic, json) {
    const c = this.byTopic.get(topic);
    const tNs = BigInt(Math.max(0, this.run.tUs())) * 1000n;
    const payload = Buffer.from(json, 'utf8');
    if (c.latched) this.latest.set(c.id, [tNs, payload]);
    for (const s of this.sessions) this.offer(s, c.id, tNs, payload);
  }

  // One control step, reported in the run's order (simulation.cpp MonitorModel::sample);
  // the step reports built only for a channel someone subscribed to (run_channels.cpp).
  step() {
    const run = this.run;
    const changes = run.advance();
    const newSecond = run.step === 1 || Math.floor((run.tUs()) / 1e6) > Math.floor((run.tUs() - STEP_US) / 1e6);
    if (newSecond) this.publish('/rilbed/world', run.worldJson());
    for (const c of changes) this.publish('/rilbed/events', run.eventJson(c));
    if (this.subscribed('/rilbed/poses')) this.publish('/rilbed/poses', run.posesJson());
    if (this.subscribed('/rilbed/scene')) this.publish('/rilbed/scene', run.sceneJson());
    if (this.subscribed('/rilbed/wheels')) this.publish('/rilbed/wheels', run.wheelsJson());
    if (this.subscribed('/rilbed/sensors')) this.publish('/rilbed/sensors', run.sensorsJson());
    if (newSecond) this.publish('/rilbed/status', run.statusJson());
  }

  // Steps as fast as the clients take them (each step waits for the sockets to drain).
  async fastForward(steps) {
    for (let i = 0; i < steps; ++i) {
      this.step();
      while ([...this.sessions].some((s) => s.ws.bufferedAmount > 512 * 1024)) await sleep(2);
    }
  }

  // Real time: a step every 100 ms of the wall clock, without drift.
  startRealtime() {
    const t0 = performance.now();
    let k = 0;
    const tick = () => {
      k += 1;
      this.step();
      this.timer = setTimeout(tick, Math.max(0, t0 + (k + 1) * (STEP_US / 1000) - performance.now()));
    };
    this.timer = setTimeout(tick, STEP_US / 1000);
  }

  async close() {
    clearTimeout(this.timer);
    for (const s of this.sessions) s.ws.terminate();
    await new Promise((resolve) => this.http.close(resolve));
  }
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// ---------------------------------------------------------------- in the page
// Installed before the page's scripts: times each requestAnimationFrame callback named
// `draw` (app.js's live view), and can ask for a redraw every frame.
const PAGE_PROBE = () => {
  const raf = window.requestAnimationFrame.bind(window);
  const B = (window.__drawBench = { on: false, draws: [], pumping: false });
  window.requestAnimationFrame = function requestAnimationFrame(cb) {
    if (typeof cb !== 'function' || cb.name !== 'draw') return raf(cb);
    return raf((ts) => {
      const t0 = performance.now();
      try {
        cb(ts);
      } finally {
        if (B.on) B.draws.push(ts, performance.now() - t0);
      }
    });
  };
  // Zooming the view, a step a frame: a wheel event on the live view every frame, in and
  // out in turn by 0.15% about its centre (app.js redraws for each, as for a drag), so
  // that every frame is drawn anew at a new scale, as when someone zooms or pans.
  let sign = 1;
  B.pump = () => {
    if (!B.pumping) return;
    const c = document.getElementById('view');
    const r = c.getBoundingClientRect();
    sign = -sign;
    c.dispatchEvent(new WheelEvent('wheel', { deltaY: sign, clientX: r.left + r.width / 2, clientY: r.top + r.height / 2,
      bubbles: true, cancelable: true }));
    raf(B.pump);
  };
};

const quantile = (sorted, q) => {
  if (!sorted.length) return NaN;
  const i = (sorted.length - 1) * q, lo = Math.floor(i), hi = Math.ceil(i);
  return sorted[lo] + (sorted[hi] - sorted[lo]) * (i - lo);
};

async function measure(page, server, seconds, warmup, redraw) {
  await page.evaluate((on) => { const B = window.__drawBench; B.pumping = on; if (on) B.pump(); }, redraw);
  await sleep(warmup * 1000);
  const posesBefore = server.counts.posesSent, droppedBefore = server.counts.dropped, cpuBefore = process.cpuUsage();
  const start = await page.evaluate(() => {
    const B = window.__drawBench;
    B.draws = []; B.on = true;
    return { t: performance.now(), frames: window.rilbed.stats.frames };
  });
  await sleep(seconds * 1000);
  const end = await page.evaluate(() => {
    const B = window.__drawBench;
    B.on = false; B.pumping = false;
    return { t: performance.now(), frames: window.rilbed.stats.frames, draws: B.draws };
  });
  const elapsed = (end.t - start.t) / 1000;
  const ts = [], js = [];
  for (let i = 0; i < end.draws.length; i += 2) { ts.push(end.draws[i]); js.push(end.draws[i + 1]); }
  const intervals = ts.slice(1).map((t, i) => t - ts[i]).sort((a, b) => a - b);
  js.sort((a, b) => a - b);
  return {
    fps: (end.frames - start.frames) / elapsed,
    wrapped: ts.length,
    intervalMedian: quantile(intervals, 0.5), intervalP95: quantile(intervals, 0.95), intervalMax: intervals[intervals.length - 1],
    jsMedian: quantile(js, 0.5), jsP95: quantile(js, 0.95),
    posesPerS: (server.counts.posesSent - posesBefore) / elapsed,
    dropped: server.counts.dropped - droppedBefore,
    serverCpu: (() => { const u = process.cpuUsage(cpuBefore); return (u.user + u.system) / 1e6 / elapsed; })(),
  };
}

// The trails checkbox clicked (if it must change), then the mouse back on the live view.
async function setTrails(page, on) {
  const box = page.locator('input[data-overlay="trails"]');
  if ((await box.isChecked()) !== on) await box.click();
  const r = await page.locator('#view').boundingBox();
  await page.mouse.move(r.x + r.width / 2, r.y + r.height / 2);
}

// ---------------------------------------------------------------- main
async function main() {
  const args = parseArgs(process.argv.slice(2));
  const { playwright, WebSocketServer } = requirePackages();
  const browser = await playwright.chromium.launch({ executablePath: CHROMIUM, args: ['--no-sandbox'], headless: true });
  const rows = [];
  const loadBefore = os.loadavg();
  const pageErrors = [];
  let screenshot = null, gpu = null, version;
  const extraShots = [];
  const cleanup = [];
  try {
    try {
      const cdp = await browser.newBrowserCDPSession();
      const info = await cdp.send('SystemInfo.getInfo');
      gpu = { canvas: info.gpu.featureStatus?.['2d_canvas'], raster: info.gpu.featureStatus?.rasterization,
        compositing: info.gpu.featureStatus?.gpu_compositing, device: info.gpu.devices?.[0]?.deviceString };
    } catch { /* older Chromium: no GPU line */ }
    for (const n of args.robots) {
      const run = new StandInRun(n);
      const server = new StandInServer(WebSocketServer, run);
      await server.listen();
      cleanup.push(() => server.close());
      const context = await browser.newContext({ viewport: VIEWPORT, deviceScaleFactor: args.dpr });
      cleanup.push(() => context.close());
      await context.addInitScript(PAGE_PROBE);
      const page = await context.newPage();
      page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(`${n} robots: console error: ${m.text()}`); });
      page.on('pageerror', (e) => pageErrors.push(`${n} robots: uncaught: ${e.message}`));
      page.on('crash', () => pageErrors.push(`${n} robots: the page crashed`));
      await page.goto(server.url, { waitUntil: 'load' });
      await page.waitForFunction(() => document.getElementById('connection').textContent === 'connected', null, { timeout: 30000 });
      const t0 = Date.now();
      while (!server.subscribed('/rilbed/poses')) {
        if (Date.now() - t0 > 30000) throw new Error('the page did not subscribe to /rilbed/poses');
        await sleep(20);
      }
      // Trails off while fast-forwarding: the page takes the steps faster (it keeps them all the same).
      await setTrails(page, false);
      const ffStart = Date.now();
      await server.fastForward(PREFILL_STEPS);
      const lastT = run.tUs() * 1e-6;
      await page.waitForFunction((t) => window.rilbed.run.poses && window.rilbed.run.poses.t_s >= t - 1e-9, lastT,
        { timeout: 300000, polling: 100 });
      const prefill = { seconds: (Date.now() - ffStart) / 1000,
        trailPoints: await page.evaluate(() => { let k = 0; for (const t of window.rilbed.run.trails.values()) k += t.length; return k; }) };
      console.error(`# ${n} robots: fast-forwarded ${PREFILL_STEPS} steps in ${prefill.seconds.toFixed(1)} s; ` +
        `${prefill.trailPoints} trail points in the page`);
      server.startRealtime();
      await sleep(1000);
      for (const trails of [true, false]) {
        await setTrails(page, trails);
        for (const redraw of [false, true]) {
          const r = await measure(page, server, args.seconds, args.warmup, redraw);
          rows.push({ n, trails, redraw, ...r });
          console.error(`# ${n} robots, trails ${trails ? 'on' : 'off'}, ${redraw ? 'zooming' : 'live'}: ` +
            `${r.fps.toFixed(1)} frames/s`);
        }
        if (trails && n === Math.max(...args.robots)) {
          fs.mkdirSync(ARTIFACTS, { recursive: true });
          const other = WEB_ROOT === DEFAULT_WEB_ROOT ? '' : `_${path.basename(WEB_ROOT)}`; // --web: not the page's own
          screenshot = path.join(ARTIFACTS, `draw_bench_${n}${other}.png`);
          await page.screenshot({ path: screenshot });
        }
      }
      if (n === Math.max(...args.robots)) { // the rest of the page at that size, to look at
        const other = WEB_ROOT === DEFAULT_WEB_ROOT ? '' : `_${path.basename(WEB_ROOT)}`;
        const shot = async (selector, name) => {
          const file = path.join(ARTIFACTS, `draw_bench_${n}${other}_${name}.png`);
          await page.locator(selector).screenshot({ path: file });
          extraShots.push(file);
        };
        await shot('#status', 'status');
        await page.fill('#agent-filter', '12');
        await page.waitForFunction(() => [...document.querySelectorAll('#agents tbody tr')].every((tr) => tr.hidden || tr.textContent.includes('12')),
          null, { timeout: 10000 }).catch(() => {});
        await shot('#status', 'status_filtered');
        await page.fill('#agent-filter', '');
        await shot('#plots', 'plots');
      }
      rows.filter((r) => r.n === n).forEach((r) => { r.requests = server.counts.requests; r.refused = server.counts.refused; });
      await cleanup.pop()();
      await cleanup.pop()();
    }
  } finally {
    for (const f of cleanup.reverse()) await f().catch(() => {});
    version = browser.version();
    await browser.close();
  }

  // ------------------------------------------------ the report
  const f1 = (x) => (Number.isFinite(x) ? x.toFixed(1) : '—');
  const cpu = (fs.readFileSync('/proc/cpuinfo', 'utf8').match(/^model name\s*:\s*(.*)$/m) || [])[1] || 'unknown';
  let nproc = String(os.availableParallelism ? os.availableParallelism() : os.cpus().length);
  try { nproc = require('node:child_process').execFileSync('nproc').toString().trim(); } catch { /* os's count */ }
  console.log(`## The live view's drawing rate (web/tests/draw_bench.js)\n`);
  console.log('| robots | trails | view | frames/s | frame interval median (ms) | interval p95 (ms) | 5th-pct frames/s | draw() JS median / p95 (ms) | poses msgs/s | dropped |');
  console.log('| ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |');
  for (const r of rows) {
    console.log(`| ${r.n} | ${r.trails ? 'on' : 'off'} | ${r.redraw ? 'zooming' : 'live'} | ${f1(r.fps)} | ${f1(r.intervalMedian)} | ` +
      `${f1(r.intervalP95)} | ${f1(1000 / r.intervalP95)} | ${f1(r.jsMedian)} / ${f1(r.jsP95)} | ${f1(r.posesPerS)} | ${r.dropped} |`);
  }
  console.log(`
How it was measured:
- Chromium ${version}, headless (playwright-core ${require('playwright-core/package.json').version}, ${CHROMIUM} --no-sandbox)` +
  (gpu ? `; 2D canvas ${gpu.canvas}, rasterization ${gpu.raster}, compositing ${gpu.compositing} (${gpu.device})` : '') + `
- viewport ${VIEWPORT.width} x ${VIEWPORT.height} CSS px, device scale factor ${args.dpr}; the live view's canvas is the page's own size for it
- machine: nproc ${nproc}, CPU ${cpu}, Node ${process.version}; the stand-in server runs in this Node process, on the same cores;
  load average (1 min) ${loadBefore[0].toFixed(2)} at the start, ${os.loadavg()[0].toFixed(2)} at the end
- the real page (web/ as served by rilbed: token in the query, then its cookie) against a Node stand-in for \`rilbed run --gui\`:
  the run's 12 channels, schemas and JSON payloads; every 100 ms (10 Hz, the control step) poses and sensors of every robot,
  every second world and status; behaviour events as they change. ${FIELD_M} m x ${FIELD_M} m walled field, four boxes,
  virtual Kheperas at 0.08-0.12 m/s on smooth random paths; every overlay as the page starts (all on, trails as dots)
- before measuring, the run is fast-forwarded ${PREFILL_STEPS} steps (${PREFILL_STEPS / 10} s) so that every trail holds its 400 points
- each row: ${args.warmup} s warm-up, then ${args.seconds} s measured. live: the page draws when messages come (as when watched);
  zooming: a wheel event on the view every frame as well (zoom in, out, by 0.15%), each frame drawn anew, the trail layer moved with the view (60 Hz vsync is the ceiling).
  The mouse rests on the live view (Chromium hit-tests under it after layout changes, as for someone watching)
- frames/s: window.rilbed.stats.frames (one per draw()) over the window; intervals between draws and draw()'s own
  JavaScript time from a requestAnimationFrame wrapper timing the callbacks named draw (app.js unchanged). An interval
  covers all the main thread did between two draws (messages, agent table, draw(), rasterizing the canvas)
- "interval p95" is the 95th-percentile frame interval; "5th-pct frames/s" is 1000 / that: the rate the slowest 5% of frames fall below
- dropped: messages the server dropped because the page did not take them (8 MiB queue per client, as rilbed's)`);
  if (screenshot) console.log(`- screenshot of the ${Math.max(...args.robots)}-robot page, trails on: ${path.relative(REPO, screenshot)}`);
  if (extraShots.length) console.log(`- its status (agent table, unfiltered and filtered by "12") and plots: ${extraShots.map((f) => path.relative(REPO, f)).join(', ')}`);
  if (rows.length) {
    const cpu = rows.map((r) => r.serverCpu * 100);
    console.log(`- this Node process (the stand-in server, mostly) used ${Math.min(...cpu).toFixed(0)}-${Math.max(...cpu).toFixed(0)}% of a core during the windows`);
  }
  if (rows.length) console.log(`- HTTP requests to the stand-in: ${[...new Set(rows.map((r) => `${r.n} robots: ${r.requests}, ${r.refused} refused`))].join('; ')}`);
  if (pageErrors.length) console.log(`\nThe page reported errors:\n${pageErrors.slice(0, 20).map((e) => `- ${e}`).join('\n')}`);
}

if (require.main === module) {
  main().catch((e) => {
    console.error(`${NAME}: ${e.stack || e.message}`);
    process.exit(1);
  });
}
module.exports = { setWebRoot: (d) => { WEB_ROOT = path.resolve(d); }, StandInRun, StandInServer, PAGE_PROBE, measure, setTrails, requirePackages, CHROMIUM, VIEWPORT, PREFILL_STEPS };
