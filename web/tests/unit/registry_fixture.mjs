// A registry as controllers.json serves it (`rilbed controllers --json`'s shape), for the
// unit tests: two of rilbed's controllers, cut down, and one the page cannot know by name
// ("sweeper"), so that a check that passes shows it came from the registry. Its entries have
// no `library`, as controllers.json had before plug-in libraries: that reads as null.
export const REGISTRY_JSON = [
  {
    name: 'convoy', summary: 'paper 001\'s convoy', sensors: ['proximity', 'pose'], required_sensors: [],
    wants_team: true, concurrent: true, origin: 'built in', params: [],
  },
  {
    name: 'wander', summary: 'a Braitenberg wanderer', sensors: ['proximity'], required_sensors: [],
    wants_team: false, concurrent: true, origin: 'built in',
    params: [{ name: 'speed_mps', unit: 'm/s', default: 0.1, min: 0, max: 1.016, summary: 'cruising speed in the open', required: false, integer: false }],
  },
  {
    name: 'sweeper', summary: 'sweeps the floor in lanes', sensors: ['range_finders', 'track', 'proximity'],
    required_sensors: ['range_finders', 'track'], wants_team: false, concurrent: false, origin: 'plugin',
    params: [
      { name: 'lanes', unit: '', default: null, min: 1, max: 20, summary: 'how many lanes', required: true, integer: true },
      { name: 'gap_m', unit: 'm', default: 0.05, min: 0.01, max: null, summary: 'between lanes', required: false, integer: false },
      { name: 'bias', unit: '', default: 0, min: null, max: null, summary: 'any number', required: false, integer: false },
    ],
  },
];

// The plug-in libraries of a run whose scenario names their controllers, as
// controllers.json gives them: absolute paths, as the parser made them.
export const CPP_LIBRARY = '/home/me/rilbed/examples/controllers/braitenberg_cpp/build/braitenberg_cpp.so';
export const C_LIBRARY = '/home/me/rilbed/build/plugins/braitenberg.so';

// That run's registry: rilbed's own (library null) and one controller of each library.
export const LIBRARY_REGISTRY_JSON = [
  ...REGISTRY_JSON.map((e) => ({ ...e, library: null })),
  {
    name: 'braitenberg_cpp', summary: 'a Braitenberg vehicle in C++', sensors: ['proximity'], required_sensors: ['proximity'],
    wants_team: false, concurrent: true, origin: CPP_LIBRARY, library: CPP_LIBRARY,
    params: [
      { name: 'gain', unit: '', default: null, min: 0, max: 10, summary: 'how hard it turns away', required: true, integer: false },
      { name: 'speed_mps', unit: 'm/s', default: 0.08, min: 0, max: 1.016, summary: 'speed in the open', required: false, integer: false },
    ],
  },
  {
    name: 'braitenberg', summary: "the C controller 'braitenberg' of braitenberg.so", sensors: ['proximity'], required_sensors: [],
    wants_team: false, concurrent: true, origin: C_LIBRARY, library: C_LIBRARY, params: [],
  },
];
