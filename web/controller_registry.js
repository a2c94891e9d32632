// The controllers a scenario can name, as the server serves them at controllers.json: the
// same registry the scenario parser checks robots against (`rilbed controllers --json`).
// The editor keeps no list of its own, so a controller added to rilbed shows in its lists
// and forms, and is checked, without a change here.

export const REGISTRY_URL = 'controllers.json';

const isString = (v) => typeof v === 'string';
const isNumberOrNull = (v) => v === null || (typeof v === 'number' && Number.isFinite(v));
const isStringList = (v) => Array.isArray(v) && v.every(isString);

function parseParam(p, where) {
  if (!p || typeof p !== 'object' || !isString(p.name) || !p.name) throw new Error(`${where}: a parameter without a name`);
  const at = `${where}, parameter ${p.name}`;
  for (const key of ['default', 'min', 'max']) {
    if (!isNumberOrNull(p[key] ?? null)) throw new Error(`${at}: ${key} is ${JSON.stringify(p[key])}, not a number or null`);
  }
  return {
    name: p.name, unit: isString(p.unit) ? p.unit : '', summary: isString(p.summary) ? p.summary : '',
    default: p.default ?? null, min: p.min ?? null, max: p.max ?? null,
    required: p.required === true, integer: p.integer === true,
  };
}

function parseEntry(e, k) {
  if (!e || typeof e !== 'object' || !isString(e.name) || !e.name) throw new Error(`entry ${k} has no name`);
  const where = `controller ${e.name}`;
  if (!Array.isArray(e.params)) throw new Error(`${where}: params is not a list`);
  for (const key of ['sensors', 'required_sensors']) {
    if (!isStringList(e[key] ?? [])) throw new Error(`${where}: ${key} is not a list of names`);
  }
  return {
    name: e.name, summary: isString(e.summary) ? e.summary : '', origin: isString(e.origin) ? e.origin : '',
    sensors: e.sensors ?? [], required_sensors: e.required_sensors ?? [],
    wants_team: e.wants_team === true, concurrent: e.concurrent === true,
    params: e.params.map((p) => parseParam(p, where)),
  };
}

export class ControllerRegistry {
  constructor(entries) {
    this.entries = entries;
    this.byName = new Map(entries.map((e) => [e.name, e]));
  }

  get names() { return this.entries.map((e) => e.name); }

  // The entry of controller `name`, or undefined.
  find(name) { return this.byName.get(name); }
}

// The registry from controllers.json's parsed JSON; throws, saying what is wrong, when it
// is not a list of controllers as `rilbed controllers --json` writes them.
export function parseRegistry(json) {
  if (!Array.isArray(json)) throw new Error(`${REGISTRY_URL} is not a list of controllers`);
  const entries = json.map(parseEntry);
  const seen = new Set();
  for (const e of entries) {
    if (seen.has(e.name)) throw new Error(`${REGISTRY_URL} names controller ${e.name} twice`);
    seen.add(e.name);
  }
  if (!entries.length) throw new Error(`${REGISTRY_URL} lists no controller`);
  return new ControllerRegistry(entries);
}

// Fetches and parses the registry (`fetchImpl`: fetch, or a stand-in); rejects with an
// Error saying what failed (the request, the status, the JSON or its shape).
export async function loadRegistry(fetchImpl = globalThis.fetch, url = REGISTRY_URL) {
  let response;
  try {
    response = await fetchImpl(url, { cache: 'no-store' });
  } catch (e) {
    throw new Error(`GET ${url} failed: ${e.message}`, { cause: e });
  }
  if (!response.ok) throw new Error(`GET ${url} answered ${response.status} ${response.statusText || ''}`.trim());
  let json;
  try {
    json = await response.json();
  } catch (e) {
    throw new Error(`${url} is not JSON: ${e.message}`, { cause: e });
  }
  return parseRegistry(json);
}

// A number as the C++ writes it in its messages: whole ones without a point.
export const numberText = (v) => (Number.isInteger(v) ? String(v) : String(Number(v.toPrecision(6))));

// A parameter's allowed values: "0 to 1.016", "at least 1", "any".
export function rangeText(p) {
  if (p.min !== null && p.max !== null) return `${numberText(p.min)} to ${numberText(p.max)}`;
  if (p.min !== null) return `at least ${numberText(p.min)}`;
  if (p.max !== null) return `at most ${numberText(p.max)}`;
  return 'any';
}

export const withUnit = (p) => (p.unit ? ` (${p.unit})` : '');

// What a parameter's input says when a person hovers it: what it is, its range, its default.
export function paramDescription(p) {
  const fallback = p.required ? 'required' : p.default !== null ? `default ${numberText(p.default)}` : 'no default';
  return `${p.summary} [${rangeText(p)}${withUnit(p)}${p.integer ? ', whole' : ''}; ${fallback}]`;
}
