// The controller registry (web/controller_registry.js): controllers.json parsed and
// checked, fetched with its failures said, its numbers written as the C++ writes them.
import test from 'node:test';
import assert from 'node:assert/strict';
import { loadRegistry, numberText, paramDescription, parseRegistry, rangeText } from '../../controller_registry.js';
import { REGISTRY_JSON } from './registry_fixture.mjs';

const copy = () => JSON.parse(JSON.stringify(REGISTRY_JSON));

test('parseRegistry keeps every controller in order, found by name', () => {
  const r = parseRegistry(copy());
  assert.deepEqual(r.names, ['convoy', 'wander', 'sweeper']);
  assert.equal(r.find('sweeper').required_sensors[1], 'track');
  assert.equal(r.find('wander').params[0].unit, 'm/s');
  assert.equal(r.find('sweeper').params[1].max, null);
  assert.equal(r.find('nothing'), undefined);
});

test('parseRegistry refuses what is not a registry, saying what is wrong', () => {
  assert.throws(() => parseRegistry({ controllers: [] }), /controllers\.json is not a list of controllers/);
  assert.throws(() => parseRegistry([]), /lists no controller/);
  assert.throws(() => parseRegistry([{ summary: 'x', params: [] }]), /entry 0 has no name/);
  const twice = copy(); twice.push(copy()[1]);
  assert.throws(() => parseRegistry(twice), /names controller wander twice/);
  const noParams = copy(); delete noParams[1].params;
  assert.throws(() => parseRegistry(noParams), /controller wander: params is not a list/);
  const badMin = copy(); badMin[1].params[0].min = '0';
  assert.throws(() => parseRegistry(badMin), /controller wander, parameter speed_mps: min is "0", not a number or null/);
  const badSensors = copy(); badSensors[2].required_sensors = 'track';
  assert.throws(() => parseRegistry(badSensors), /controller sweeper: required_sensors is not a list of names/);
});

const answer = (status, body, statusText = '') => async () => ({
  ok: status >= 200 && status < 300, status, statusText,
  json: async () => (typeof body === 'string' ? JSON.parse(body) : body),
});

test('loadRegistry fetches controllers.json, not cached', async () => {
  const asked = [];
  const r = await loadRegistry(async (url, options) => { asked.push([url, options.cache]); return answer(200, copy())(); });
  assert.deepEqual(asked, [['controllers.json', 'no-store']]);
  assert.deepEqual(r.names, ['convoy', 'wander', 'sweeper']);
});

test('loadRegistry says why it has no registry: the request, the status, the JSON', async () => {
  await assert.rejects(loadRegistry(async () => { throw new TypeError('Failed to fetch'); }), /GET controllers\.json failed: Failed to fetch/);
  await assert.rejects(loadRegistry(answer(401, 'no', 'Unauthorized')), /GET controllers\.json answered 401 Unauthorized/);
  await assert.rejects(loadRegistry(answer(200, '<html>')), /controllers\.json is not JSON/);
  await assert.rejects(loadRegistry(answer(200, { name: 'wander' })), /not a list of controllers/);
});

test('numbers and ranges read as the scenario parser writes them', () => {
  assert.equal(numberText(1000000), '1000000');
  assert.equal(numberText(1.016), '1.016');
  assert.equal(numberText(0.1 + 0.2), '0.3');
  const [lanes, gap, bias] = parseRegistry(copy()).find('sweeper').params;
  assert.equal(rangeText(lanes), '1 to 20');
  assert.equal(rangeText(gap), 'at least 0.01');
  assert.equal(rangeText(bias), 'any');
  assert.equal(rangeText({ min: null, max: 3 }), 'at most 3');
});

test('a parameter\'s description: its summary, range, unit and default', () => {
  const r = parseRegistry(copy());
  assert.equal(paramDescription(r.find('wander').params[0]), 'cruising speed in the open [0 to 1.016 (m/s); default 0.1]');
  assert.equal(paramDescription(r.find('sweeper').params[0]), 'how many lanes [1 to 20, whole; required]');
});
