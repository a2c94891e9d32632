#!/usr/bin/env node
// The web panel's server as a Foxglove client sees it, with the client the
// panel's tests and Foxglove's own tools use: @foxglove/ws-protocol over the `ws` package.
//
//   node web/tests/protocol_test.js RILBED SCENARIO
//
// Starts `RILBED run SCENARIO --realtime --duration 60 --gui --gui-port 0 --out TMPDIR`,
// reads the page's URL from its stdout, connects to ws://127.0.0.1:PORT/ws?token=TOKEN
// and checks: the server's info; every rilbed channel advertised (JSON, with a JSON
// Schema); the run's poses (every robot of the scenario, inside the field); a pause, a
// resume and an exit published on /rilbed/console, each accepted on
// /rilbed/console_reply, the pause seen on /rilbed/status; and the run exiting with 0,
// its folder recording who paused it; the vision settings set and read back through the
// client's parameters (setParameters, getParameters), and an out-of-range one refused. Every wait has a deadline; on any failure it says
// what it was waiting for, shows the end of rilbed's output, kills rilbed and exits 1.
// CTest runs it as web_protocol (label e2e); `./run test` installs its npm packages.
'use strict';

const fs = require('node:fs');
const path = require('node:path');
const {
  ok, check, fail, poke, abort, waitFor, describeExit, startRilbed, commandLine, checkBinary, checkScenario,
  tempFolder, requirePackage, run,
} = require('./support');

const TOPICS = [
  '/rilbed/world', '/rilbed/status', '/rilbed/poses', '/rilbed/wheels', '/rilbed/sensors',
  '/rilbed/detections', '/rilbed/events', '/rilbed/summary', '/rilbed/scene', '/rilbed/console_reply',
];
// How far a robot's centre may be outside the field's rectangle (a real robot's pose is
// what the camera saw, which can be a little off at a wall).
const FIELD_TOLERANCE_M = 0.02;

// ---------------------------------------------------------------- the scenario's robots
// The robot IDs a scenario file names: `id: N` or `ids: LIST` (LIST as `1-3,5`) in its
// `robots:` list, block or flow style. Returns [] when it finds none (then the run's own
// /rilbed/world says which robots there are).
function scenarioRobotIds(text) {
  const lines = text.split('\n');
  const start = lines.findIndex((l) => /^robots\s*:/.test(l));
  if (start < 0) return [];
  let section = lines[start].replace(/^robots\s*:/, '');
  for (let i = start + 1; i < lines.length && !/^[^\s#]/.test(lines[i]); i++) section += '\n' + lines[i];
  section = section.replace(/#.*$/gm, '');
  const ids = new Set();
  for (const m of section.matchAll(/(?:^|[\s{,-])(ids?)\s*:\s*("[^"\n]*"|'[^'\n]*'|[^}\n]*)/g)) {
    for (const raw of m[2].replace(/^["']|["']$/g, '').split(',')) {
      const item = raw.trim();
      const range = /^(\d+)(?:\s*-\s*(\d+))?$/.exec(item);
      if (!range) break;  // the next key of a flow mapping: `{ids: 1-3, pose: random}`
      const lo = Number(range[1]);
      const hi = range[2] === undefined ? lo : Number(range[2]);
      for (let id = lo; id <= hi && id - lo < 100000; id++) ids.add(id);
    }
  }
  return [...ids].sort((a, b) => a - b);
}

// ---------------------------------------------------------------- the test
async function main(state) {
  const [binary, scenario] = commandLine('RILBED SCENARIO');
  checkBinary(binary);
  checkScenario(scenario);
  const { FoxgloveClient } = requirePackage('@foxglove/ws-protocol');
  const WebSocket = requirePackage('ws');

  const scenarioIds = scenarioRobotIds(fs.readFileSync(scenario, 'utf8'));
  console.log(`# scenario ${scenario}: robots ${scenarioIds.length ? scenarioIds.join(',') : '(none found in the file: taken from /rilbed/world)'}`);

  tempFolder(state, 'protocol');
  // The page's URL on rilbed's stdout.
  const { child, runDir, port, token } = await startRilbed(state, binary, scenario, { dir: 'run', duration: 60 });
  ok(`rilbed serves its page on port ${port} (token of ${token.length} characters)`);

  // The Foxglove client.
  const url = `ws://127.0.0.1:${port}/ws?token=${token}`;
  const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
  state.client = client;
  const seen = {
    open: false, serverInfo: null, channels: new Map(), statusMessages: [], subscriptions: new Map(),
    messages: Object.fromEntries(TOPICS.map((t) => [t, []])),
  };
  const decoder = new TextDecoder();
  client.on('open', () => { seen.open = true; poke(); });
  client.on('error', (e) => state.closeExpected || abort(`WebSocket error (${e && e.message ? e.message : e})`));
  client.on('close', (e) => {
    if (!state.closeExpected) abort(`the WebSocket closed (code ${e && e.code}${e && e.reason ? `, ${e.reason}` : ''})`);
  });
  client.on('serverInfo', (info) => { seen.serverInfo = info; poke(); });
  seen.parameterValues = [];
  client.on('parameterValues', (event) => { seen.parameterValues.push(event); poke(); });
  client.on('status', (s) => {
    seen.statusMessages.push(s);
    console.log(`# server status (level ${s.level}): ${s.message}`);
    poke();
  });
  client.on('advertise', (channels) => {
    for (const c of channels) seen.channels.set(c.topic, c);
    poke();
  });
  client.on('message', ({ subscriptionId, data }) => {
    const topic = seen.subscriptions.get(subscriptionId);
    if (!topic) return;
    const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    const text = decoder.decode(bytes);
    let message;
    try {
      message = JSON.parse(text);
    } catch (e) {
      abort(`a message on ${topic} is not JSON (${e.message}): ${text.slice(0, 200)}`);
      return;
    }
    seen.messages[topic].push(message);
    poke();
  });

  await waitFor(`the WebSocket to open (${url.replace(token, 'TOKEN')})`, () => seen.open);
  ok('the WebSocket opened with subprotocol foxglove.websocket.v1 and the token');

  const info = await waitFor('serverInfo', () => seen.serverInfo);
  check((info.capabilities || []).includes('clientPublish'),
    `serverInfo's capabilities ${JSON.stringify(info.capabilities)} lack clientPublish (the console needs it)`);
  check(!info.supportedEncodings || info.supportedEncodings.includes('json'),
    `serverInfo's supportedEncodings ${JSON.stringify(info.supportedEncodings)} lack json`);
  ok(`serverInfo: name "${info.name}", capabilities ${JSON.stringify(info.capabilities)}, ` +
     `supportedEncodings ${JSON.stringify(info.supportedEncodings)}`);

  await waitFor(`the channels ${TOPICS.join(' ')} to be advertised`, () => TOPICS.every((t) => seen.channels.has(t)))
    .catch((e) => fail(`${e.message} (advertised: ${[...seen.channels.keys()].join(' ') || 'none'})`));
  for (const topic of TOPICS) {
    const c = seen.channels.get(topic);
    check(c.encoding === 'json', `${topic}'s encoding is ${JSON.stringify(c.encoding)}, not "json"`);
    check(c.schemaEncoding === 'jsonschema', `${topic}'s schemaEncoding is ${JSON.stringify(c.schemaEncoding)}, not "jsonschema"`);
    let schema;
    try {
      schema = JSON.parse(c.schema);
    } catch (e) {
      fail(`${topic}'s schema is not JSON (${e.message})`);
    }
    check(schema && schema.type === 'object', `${topic}'s schema is not an object's: ${c.schema.slice(0, 200)}`);
    check(typeof c.schemaName === 'string' && c.schemaName.length > 0, `${topic} has no schemaName`);
  }
  check(seen.channels.get('/rilbed/scene').schemaName === 'foxglove.SceneUpdate',
    `/rilbed/scene's schemaName is ${JSON.stringify(seen.channels.get('/rilbed/scene').schemaName)}, not foxglove.SceneUpdate`);
  ok(`all ${TOPICS.length} rilbed channels advertised, encoding json, schemaEncoding jsonschema, schemas parse ` +
     `(${TOPICS.map((t) => `${t}: ${seen.channels.get(t).schemaName}`).join(', ')})`);

  for (const topic of ['/rilbed/world', '/rilbed/poses', '/rilbed/status', '/rilbed/console_reply']) {
    seen.subscriptions.set(client.subscribe(seen.channels.get(topic).id), topic);
  }
  ok('subscribed to /rilbed/world, /rilbed/poses, /rilbed/status and /rilbed/console_reply');

  // The field and the robots, as the run says.
  const world = await waitFor('a message on /rilbed/world (latched: the run\'s field and robots)',
    () => seen.messages['/rilbed/world'][0]);
  check(Number.isFinite(world.width_m) && world.width_m > 0 && Number.isFinite(world.height_m) && world.height_m > 0,
    `/rilbed/world's field is ${world.width_m} x ${world.height_m} m`);
  const worldIds = (world.robots || []).map((r) => r.id).sort((a, b) => a - b);
  const realIds = new Set((world.robots || []).filter((r) => r.real).map((r) => r.id));
  if (scenarioIds.length) {
    check(JSON.stringify(worldIds) === JSON.stringify(scenarioIds),
      `/rilbed/world's robots ${worldIds.join(',')} are not the scenario's ${scenarioIds.join(',')}`);
  }
  const expectedIds = scenarioIds.length ? scenarioIds : worldIds;
  check(expectedIds.length > 0, 'the run has no robots');
  ok(`/rilbed/world: scenario "${world.scenario}", field ${world.width_m} x ${world.height_m} m, robots ` +
     `${worldIds.join(',')} (real: ${[...realIds].join(',') || 'none'})`);

  // Three poses messages, each with every robot inside the field.
  const poses = await waitFor('3 messages on /rilbed/poses', () => {
    const all = seen.messages['/rilbed/poses'];
    return all.length >= 3 && all.slice(0, 3);
  });
  for (const [i, p] of poses.entries()) {
    check(Array.isArray(p.robots), `poses message ${i + 1} has no robots list: ${JSON.stringify(p).slice(0, 300)}`);
    const byId = new Map(p.robots.map((r) => [r.id, r]));
    for (const id of expectedIds) {
      const r = byId.get(id);
      check(r, `poses message ${i + 1} (t_s ${p.t_s}) lacks robot ${id}: ${JSON.stringify(p).slice(0, 500)}`);
      check(Number.isFinite(r.x_m) && Number.isFinite(r.y_m),
        `poses message ${i + 1} (t_s ${p.t_s}): robot ${id} is at (${r.x_m}, ${r.y_m}), not finite`);
      check(r.x_m >= -FIELD_TOLERANCE_M && r.x_m <= world.width_m + FIELD_TOLERANCE_M &&
            r.y_m >= -FIELD_TOLERANCE_M && r.y_m <= world.height_m + FIELD_TOLERANCE_M,
        `poses message ${i + 1} (t_s ${p.t_s}): robot ${id} at (${r.x_m}, ${r.y_m}) is outside the ` +
        `${world.width_m} x ${world.height_m} m field`);
      check(r.real === realIds.has(id), `poses message ${i + 1}: robot ${id} has real=${r.real}, /rilbed/world says ${realIds.has(id)}`);
      check(typeof r.behaviour === 'string' && typeof r.health === 'string',
        `poses message ${i + 1}: robot ${id} lacks behaviour or health: ${JSON.stringify(r)}`);
    }
    check(p.robots.length === expectedIds.length,
      `poses message ${i + 1} has ${p.robots.length} robots, the run ${expectedIds.length}`);
  }
  const last = poses[2];
  ok(`3 poses messages (t_s ${poses.map((p) => p.t_s).join(', ')}) with robots ${expectedIds.join(',')}, each at a ` +
     `finite position inside the field; e.g. ${last.robots.slice(0, 2).map((r) =>
       `robot ${r.id} (${r.x_m.toFixed(3)}, ${r.y_m.toFixed(3)}) ${r.behaviour}/${r.health}`).join(', ')}`);

  // The console.
  const consoleChannel = client.advertise({ topic: '/rilbed/console', encoding: 'json', schemaName: 'rilbed.console' });
  ok(`advertised client channel /rilbed/console (id ${consoleChannel}, encoding json, schemaName rilbed.console)`);
  const encoder = new TextEncoder();
  // Publishes a command, waits for its reply; returns [reply, the index of the first status after sending].
  const command = async (name, args = []) => {
    const replies = seen.messages['/rilbed/console_reply'];
    const before = replies.length;
    const statusFrom = seen.messages['/rilbed/status'].length;
    client.sendMessage(consoleChannel, encoder.encode(JSON.stringify({ command: name, args })));
    const reply = await waitFor(`a message on /rilbed/console_reply answering ${name}`, () => replies[before]);
    check(reply.accepted === true, `${name} was not accepted: ${JSON.stringify(reply)}`);
    ok(`${name} published on /rilbed/console, accepted on /rilbed/console_reply: ${JSON.stringify(reply)}`);
    return statusFrom;
  };
  const statusSince = (from, what, test) => waitFor(what, () => seen.messages['/rilbed/status'].slice(from).find(test));

  let from = await command('pause');
  const paused = await statusSince(from, 'a message on /rilbed/status with state "paused" after the pause',
    (s) => s.state === 'paused');
  ok(`/rilbed/status says paused (t_s ${paused.t_s}, scenario "${paused.scenario}", ${paused.robots} robots, ` +
     `${paused.real_robots} real)`);
  check(paused.robots === expectedIds.length, `/rilbed/status counts ${paused.robots} robots, the run has ${expectedIds.length}`);
  check(paused.real_robots === realIds.size, `/rilbed/status counts ${paused.real_robots} real robots, /rilbed/world ${realIds.size}`);

  from = await command('resume');
  const running = await statusSince(from, 'a message on /rilbed/status with state "running" after the resume',
    (s) => s.state === 'running');
  ok(`/rilbed/status says running again (t_s ${running.t_s})`);

  // The vision settings, as Foxglove's own client sets parameters.
  for (const capability of ['parameters', 'parametersSubscribe']) {
    check((info.capabilities || []).includes(capability), `serverInfo's capabilities lack ${capability}`);
  }
  const answerTo = (id) => waitFor(`parameterValues answering ${id}`, () => seen.parameterValues.find((e) => e.id === id));
  const valueOf = (event, name) => (event.parameters.find((p) => p.name === name) || {}).value;
  client.setParameters([{ name: 'vision.min_score', value: 0.7 }, { name: 'vision.brightness', value: -10 }], 'set-1');
  const set = await answerTo('set-1');
  check(valueOf(set, 'vision.min_score') === 0.7 && valueOf(set, 'vision.brightness') === -10,
    `setParameters' answer does not carry the new values: ${JSON.stringify(set)}`);
  client.getParameters([], 'get-1');
  const all = await answerTo('get-1');
  const names = all.parameters.map((p) => p.name).sort();
  check(JSON.stringify(names) === JSON.stringify(['vision.brightness', 'vision.contrast', 'vision.max_diameter_px',
    'vision.min_diameter_px', 'vision.min_score', 'vision.threshold']), `getParameters gave ${JSON.stringify(names)}`);
  check(valueOf(all, 'vision.min_score') === 0.7, `getParameters' min_score is ${valueOf(all, 'vision.min_score')}, not 0.7`);
  ok(`parameters: setParameters accepted (${JSON.stringify(set.parameters)}), getParameters lists ${names.length}`);
  const statusBefore = seen.statusMessages.length;
  client.setParameters([{ name: 'vision.threshold', value: 1000 }], 'set-2');
  const refused = await answerTo('set-2');
  check(valueOf(refused, 'vision.threshold') === 24, `a refused threshold changed it: ${JSON.stringify(refused)}`);
  const why = seen.statusMessages.slice(statusBefore).find((s) => s.level === 2);
  check(why && why.message.includes('threshold 1000 is outside 1..255'), `no error status for threshold 1000: ${JSON.stringify(why)}`);
  ok(`parameters: threshold 1000 refused ("${why.message}"), the value stays 24`);

  // The exit: the run ends, its server with it; its reply may or may not get out first.
  state.closeExpected = true;
  child.exitExpected = true;
  const exitStatusFrom = seen.messages['/rilbed/status'].length;
  client.sendMessage(consoleChannel, encoder.encode(JSON.stringify({ command: 'exit', args: [] })));
  ok('exit published on /rilbed/console');
  const exit = await waitFor('rilbed to exit after the exit command', () => child.exit);
  check(exit.code === 0, `rilbed ended with ${describeExit(exit)}, not exit code 0`);
  const exitReply = seen.messages['/rilbed/console_reply'].find((r) => r.reason && /exit|end/.test(r.reason));
  const ended = seen.messages['/rilbed/status'].slice(exitStatusFrom).find((s) => s.state === 'ended');
  ok(`rilbed exited with code 0 (exit's reply: ${exitReply ? JSON.stringify(exitReply) : 'not seen before the socket closed'}` +
     `; last status: ${ended ? `ended by ${ended.ended_by}` : 'not seen'})`);

  // The run's folder records the console's commands.
  const eventsFile = path.join(runDir, 'events.csv');
  check(fs.existsSync(eventsFile), `the run wrote no ${eventsFile}`);
  const events = fs.readFileSync(eventsFile, 'utf8');
  for (const what of ['paused by ', 'resumed by ', 'ended by ']) {
    check(events.includes(`,console,0,0,${what}`), `${eventsFile} has no console event "${what}...":\n${events.slice(-1000)}`);
  }
  ok(`the run's events.csv records the pause, the resume and the exit (${events.split('\n')
    .filter((l) => l.includes(',console,')).map((l) => l.split(',').slice(4).join(',')).join('; ')})`);
}

run(main, {
  name: 'protocol_test',
  summary: (passed, failed) => `${passed} passed, ${failed} failed`,
  teardown: (state) => {
    if (!state.client) return;
    state.closeExpected = true;
    try { state.client.close(); } catch (_) { /* already closed */ }
  },
});
