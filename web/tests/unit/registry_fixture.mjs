// A registry as controllers.json serves it (`rilbed controllers --json`'s shape), for the
// unit tests: two of rilbed's controllers, cut down, and one the page cannot know by name
// ("sweeper"), so that a check that passes shows it came from the registry.
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
