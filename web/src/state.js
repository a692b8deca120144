// One state object and its events (three.js editor style, docs/design.md section 2): panels never
// call each other; they read `state`, change it with set(), and listen with on(key, fn). Every
// key of a set() call fires that key's listeners once, after all keys are assigned.
export const state = {
  me: null,           // GET /api/auth/me: {mode, user, display_name, role, namespace} (none mode: the teacher, user null)
  session: null,      // this tab's session id (never 'default')
  scene: null,        // the session's full scene JSON, as the server last answered it
  stats: null,        // latest GET /stats reply
  convergence: null,  // latest GET /convergence reply (+ session), while the Convergence tab is shown
  health: null,       // GET /api/health reply (device name)
  selected: 0,        // the object the editor and the Parameters panel work on (Objects tab)
  brdf: null,         // the BRDF objects[selected] uses: {name, params:[{name,type,min,max,default}]}
  diagnostics: [],    // latest compile diagnostics [{line, column, severity, message}]
  status: '',         // one line for the user
  library: [],        // GET /api/brdfs (sorted by name), refreshed after a save or delete
  editing: null,      // what the editor holds: {name (null: untitled/scratch), builtin, source (stored text)}
  assets: null,       // GET /api/assets, refreshed after an upload
  tab: '',            // the right-hand column's page (tabs.js)
  visible: document.visibilityState === 'visible',   // document.visibilityState === 'visible': a hidden tab pauses stream and stats
  speeds: { move: 1.5, look: 0.25 },  // camera: units per second, degrees per pixel (UI only)
  firstFrame: false,  // the viewer has shown a frame since the page loaded
};

const listeners = new Map();

export function on(key, fn) {
  if (!listeners.has(key)) listeners.set(key, []);
  listeners.get(key).push(fn);
}

export function set(changes) {
  Object.assign(state, changes);
  for (const key of Object.keys(changes)) for (const fn of listeners.get(key) || []) fn(state);
}
