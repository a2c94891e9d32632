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
  if (!(e.library === undefined || e.library === null || (isString(e.library) && e.library.startsWith('/')))) {
    throw new Error(`${where}: library is ${JSON.stringify(e.library)}, not an absolute path or null`);
  }
  return {
    name: e.name, summary: isString(e.summary) ? e.summary : '', origin: isString(e.origin) ? e.origin : '',
    library: e.library ?? null,
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

  // The entry a robot's controller names ({name, library}, scenario.js's controllerRef):
  // the one of that name if it comes from that plug-in library, or from none when no
  // library is given; else undefined. Names are unique in a registry, but a name alone does
  // not name a library's controller: the scenario parser refuses it.
  match(ref) {
    const c = ref?.name ? this.find(ref.name) : undefined;
    if (!c) return undefined;
    if (!c.library || !ref.library) return !c.library && !ref.library ? c : undefined;
    return sameLibrary(c.library, ref.library) ? c : undefined;
  }

  // The entries from plug-in library `path` (as a scenario gives it).
  fromLibrary(path) { return this.entries.filter((e) => e.library && sameLibrary(e.library, path)); }

  // The plug-in libraries' paths, each once.
  get libraries() { return [...new Set(this.entries.map((e) => e.library).filter(Boolean))]; }
}

// A path with `.`, `..` and doubled slashes taken out, as C++'s lexically_normal does.
function normalPath(path) {
  const absolute = path.startsWith('/');
  const out = [];
  for (const part of path.split('/')) {
    if (part === '' || part === '.') continue;
    if (part !== '..') out.push(part);
    else if (out.length && out[out.length - 1] !== '..') out.pop();
    else if (!absolute) out.push(part); // (above / is / itself)
  }
  return (absolute ? '/' : '') + out.join('/');
}

// Whether plug-in library `given`, as a scenario writes it, can be `registered`, the
// absolute path the registry has. The parser makes a relative path absolute from the
// scenario file's folder, which the page is not told (a file opened in a browser comes
// without one): so a relative path matches a registered one that ends with it, past its
// leading `..`s, and only an absolute one must be the same path.
export function sameLibrary(registered, given) {
  const r = normalPath(registered), g = normalPath(given);
  if (g.startsWith('/')) return r === g;
  const tail = g.replace(/^(?:\.\.\/)*(?:\.\.$)?/, '');
  return tail !== '' && r.endsWith(`/${tail}`);
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

// A plug-in library's file name, which the editor's lists show beside its controllers'
// names so that a person sees which are a library's, and which library's (the whole path,
// too long for a list, is in their titles).
export const libraryFile = (path) => path.split('/').filter(Boolean).pop() ?? path;

// A controller as the editor's lists name it: "wander", "braitenberg_cpp (braitenberg_cpp.so)".
export const controllerLabel = (c) => (c.library ? `${c.name} (${libraryFile(c.library)})` : c.name);

// What a controller's option says when a person hovers it: its summary, and its library.
export const controllerTitle = (c) => (c.library ? `${c.summary} (from ${c.library})` : c.summary);

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
