// The controller registry (web/controller_registry.js): controllers.json parsed and
// checked, fetched with its failures said, its numbers written as the C++ writes them.
import test from 'node:test';
import assert from 'node:assert/strict';
import {
  controllerLabel, controllerTitle, libraryFile, loadRegistry, numberText, paramDescription, parseRegistry, rangeText, sameLibrary,
} from '../../controller_registry.js';
import { C_LIBRARY, CPP_LIBRARY, LIBRARY_REGISTRY_JSON, REGISTRY_JSON } from './registry_fixture.mjs';

const copy = () => JSON.parse(JSON.stringify(REGISTRY_JSON));
const withLibraries = () => parseRegistry(JSON.parse(JSON.stringify(LIBRARY_REGISTRY_JSON)));

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

test('a controller\'s library: null for rilbed\'s own (or when the key is missing), the path for a plug-in\'s', () => {
  assert.equal(parseRegistry(copy()).find('wander').library, null);
  const r = withLibraries();
  assert.equal(r.find('wander').library, null);
  assert.equal(r.find('braitenberg_cpp').library, CPP_LIBRARY);
  assert.deepEqual(r.libraries, [CPP_LIBRARY, C_LIBRARY]);
  assert.deepEqual(r.fromLibrary(CPP_LIBRARY).map((c) => c.name), ['braitenberg_cpp']);
  assert.deepEqual(r.fromLibrary('/elsewhere/braitenberg_cpp.so'), []);
  assert.deepEqual(parseRegistry(copy()).libraries, []);
});

test('parseRegistry refuses a library that is not an absolute path', () => {
  const relative = JSON.parse(JSON.stringify(LIBRARY_REGISTRY_JSON)); relative[3].library = 'build/braitenberg_cpp.so';
  assert.throws(() => parseRegistry(relative), /controller braitenberg_cpp: library is "build\/braitenberg_cpp\.so", not an absolute path or null/);
  const number = JSON.parse(JSON.stringify(LIBRARY_REGISTRY_JSON)); number[3].library = 7;
  assert.throws(() => parseRegistry(number), /library is 7/);
});

test('match: rilbed\'s own by its name alone, a library\'s by its name and that library', () => {
  const r = withLibraries();
  assert.equal(r.match({ name: 'wander', library: null }).name, 'wander');
  assert.equal(r.match({ name: 'braitenberg_cpp', library: CPP_LIBRARY }).name, 'braitenberg_cpp');
  assert.equal(r.match({ name: 'braitenberg', library: C_LIBRARY }).library, C_LIBRARY);
  // A name alone does not name a library's controller (the parser refuses it), a library
  // does not name a built-in, and a library's controller is not another library's.
  assert.equal(r.match({ name: 'braitenberg_cpp', library: null }), undefined);
  assert.equal(r.match({ name: 'wander', library: CPP_LIBRARY }), undefined);
  assert.equal(r.match({ name: 'braitenberg_cpp', library: C_LIBRARY }), undefined);
  assert.equal(r.match({ name: 'braitenberg_cpp', library: '/elsewhere/braitenberg_cpp.so' }), undefined);
  assert.equal(r.match({ name: 'nothing', library: CPP_LIBRARY }), undefined);
  assert.equal(r.match({ name: null, library: CPP_LIBRARY }), undefined);
  assert.equal(r.match(null), undefined);
});

test('a library path as a scenario writes it: absolute, the same path; relative to the file, a tail of it', () => {
  assert.equal(sameLibrary(CPP_LIBRARY, CPP_LIBRARY), true);
  assert.equal(sameLibrary(CPP_LIBRARY, '/home/me/rilbed/examples/controllers/braitenberg_cpp/./build//../build/braitenberg_cpp.so'), true);
  assert.equal(sameLibrary(CPP_LIBRARY, '/home/me/braitenberg_cpp/build/braitenberg_cpp.so'), false);
  // The page is not told the scenario file's folder: a relative path matches what it can be.
  assert.equal(sameLibrary(CPP_LIBRARY, 'build/braitenberg_cpp.so'), true);
  assert.equal(sameLibrary(CPP_LIBRARY, './build/braitenberg_cpp.so'), true);
  assert.equal(sameLibrary(C_LIBRARY, '../../build/plugins/braitenberg.so'), true);
  assert.equal(sameLibrary(CPP_LIBRARY, 'braitenberg_cpp.so'), true);
  assert.equal(sameLibrary(CPP_LIBRARY, 'plugins/braitenberg_cpp.so'), false);
  assert.equal(sameLibrary(CPP_LIBRARY, 'uild/braitenberg_cpp.so'), false); // (whole names only)
  assert.equal(sameLibrary(CPP_LIBRARY, '..'), false);
  assert.equal(withLibraries().match({ name: 'braitenberg_cpp', library: 'build/braitenberg_cpp.so' }).library, CPP_LIBRARY);
});

test('how the lists show a controller: its name, and a library\'s file name; the whole path in its title', () => {
  const r = withLibraries();
  assert.equal(controllerLabel(r.find('wander')), 'wander');
  assert.equal(controllerLabel(r.find('braitenberg_cpp')), 'braitenberg_cpp (braitenberg_cpp.so)');
  assert.equal(controllerTitle(r.find('wander')), 'a Braitenberg wanderer');
  assert.equal(controllerTitle(r.find('braitenberg')), `the C controller 'braitenberg' of braitenberg.so (from ${C_LIBRARY})`);
  assert.equal(libraryFile('/a/b/c.so'), 'c.so');
  assert.equal(libraryFile('c.so'), 'c.so');
});
