// The one module that talks to the network (docs/design.md section 2). Everything else calls these
// functions and never builds a URL or calls fetch itself. Endpoints: docs/api.md.
// Identities (docs/api.md, Identities and ownership): the token this browser holds lives in
// localStorage and goes out as `Authorization: Bearer` on every request, never in a cookie or a
// URL; every request also says `X-Brdfa-Client: web`. What an <img> loads (a stream, a frame)
// cannot carry a header: those URLs carry the session's `view_key` instead, remembered here from
// the session answers that hand it out.

/** An HTTP error with the server's JSON body ({error, message, field?, diagnostics?}). */
export class ApiError extends Error {
  constructor(status, body) {
    super((body && body.message) || `HTTP ${status}`);
    this.status = status;
    this.body = body || {};
  }
}

const TOKEN_KEY = 'brdfa.token';

/** The token this browser holds, or null. */
export function getToken() {
  try { return localStorage.getItem(TOKEN_KEY); } catch { return null; }
}
export function setToken(token) {
  try { localStorage.setItem(TOKEN_KEY, token); } catch { /* storage refused: this page only */ }
}
export function clearToken() {
  try { localStorage.removeItem(TOKEN_KEY); } catch { /* nothing held */ }
}

/** The headers of every request; `anonymous` leaves the token out (joining with a code). */
function headers({ anonymous = false } = {}) {
  const h = { 'X-Brdfa-Client': 'web' };
  const token = anonymous ? null : getToken();
  if (token) h.Authorization = `Bearer ${token}`;
  return h;
}

// Called with the error when a request is answered 401 (the token was revoked meanwhile).
let unauthorized = null;
export const onUnauthorized = (fn) => { unauthorized = fn; };

async function request(method, path, { json, text, form, anonymous } = {}) {
  const init = { method, headers: headers({ anonymous }) };
  if (form !== undefined) {
    init.body = form;   // FormData: the browser sets the multipart Content-Type and boundary
  } else if (json !== undefined) {
    init.headers['Content-Type'] = 'application/json';
    init.body = JSON.stringify(json);
  } else if (text !== undefined) {
    init.headers['Content-Type'] = 'text/plain; charset=utf-8';
    init.body = text;
  }
  const res = await fetch(path, init);
  if (res.status === 204) return null;
  if (!res.ok) throw await failed(res);
  return readBody(res);
}

const readBody = (res) => ((res.headers.get('Content-Type') || '').includes('application/json') ? res.json() : res.text());

async function apiError(res) {
  const body = await readBody(res);
  return new ApiError(res.status, typeof body === 'object' ? body : { message: body });
}

async function failed(res) {
  const e = await apiError(res);
  if (res.status === 401 && unauthorized) unauthorized(e);
  return e;
}

const seg = encodeURIComponent;
/** A BRDF's path: a student's names are `alice/name`, written with the slash in the path. */
const brdfPath = (name) => String(name).split('/').map(seg).join('/');

// ---- identities ----
/** 200 {mode, user, display_name, role, namespace, quotas}; 401 without a known identity. */
export const me = () => request('GET', '/api/auth/me');
/** 201 {token, user, display_name, role}: a student's own token, from the teacher's join code. */
export const join = (code, displayName) =>
  request('POST', '/api/auth/join', { json: { code, display_name: displayName }, anonymous: true });
/** 204: the token of this request is revoked. */
export const logout = () => request('POST', '/api/auth/logout');

export const health = () => request('GET', '/api/health');

export const listBrdfs = () => request('GET', '/api/brdfs');
export const getBrdf = (name) => request('GET', `/api/brdfs/${brdfPath(name)}`);
export const validateBrdf = (source) => request('POST', '/api/brdfs/validate', { text: source });
/** Compiles and stores; 422 with `diagnostics` on a compile error (nothing stored then). */
export const putBrdf = (name, source) => request('PUT', `/api/brdfs/${brdfPath(name)}`, { text: source });
/** 204; 409 for a built-in. Removes the BRDF's presets too. */
export const deleteBrdf = (name) => request('DELETE', `/api/brdfs/${brdfPath(name)}`);

// Presets: named parameter sets of one BRDF.
export const listPresets = (brdf) => request('GET', `/api/brdfs/${brdfPath(brdf)}/presets`);
export const getPreset = (brdf, preset) => request('GET', `/api/brdfs/${brdfPath(brdf)}/presets/${seg(preset)}`);
export const putPreset = (brdf, preset, values) => request('PUT', `/api/brdfs/${brdfPath(brdf)}/presets/${seg(preset)}`, { json: values });
export const deletePreset = (brdf, preset) => request('DELETE', `/api/brdfs/${brdfPath(brdf)}/presets/${seg(preset)}`);

// Batch test jobs (the Test window). `names`: an array of BRDF names, or 'all'.
export const startValidateJob = (names) =>
  request('POST', '/api/jobs/validate', { json: names === 'all' ? { all: true } : { names } });
export const getJob = (id) => request('GET', `/api/jobs/${seg(id)}`);
/** Sampling strategies at equal time: {scene, modes?, time_ms?, reference_ms?} -> 202 {id, ...}. */
export const startConvergenceJob = (body) => request('POST', '/api/jobs/convergence', { json: body });
export const cancelJob = (id) => request('DELETE', `/api/jobs/${seg(id)}`);

// Assets: meshes, textures, environments (built-ins and uploads).
export const listAssets = (kind) => request('GET', kind ? `/api/assets?kind=${seg(kind)}` : '/api/assets');
/** multipart upload of a File; `kind` optional ('' = from the content). 201 the asset. */
export const uploadAsset = (file, kind = '') => {
  const form = new FormData();
  form.append('file', file, file.name);
  if (kind) form.append('kind', kind);
  return request('POST', '/api/assets', { form });
};

// Each session's view_key (answers of POST /api/sessions, GET /api/sessions and GET
// /api/sessions/{id}): the <img> URLs below carry it, as an <img> sends no Authorization.
const viewKeys = new Map();
function remember(s) {
  if (s && s.id && s.view_key) viewKeys.set(s.id, s.view_key);
  return s;
}
const keyParam = (session) => (viewKeys.has(session) ? `&key=${seg(viewKeys.get(session))}` : '');

/**
 * 201 {id, scene, view_key}. `scene` is optional (all defaults). `colocate`: a session the new one must
 * live beside (behind the replicas' balancer, docs/deploy.md: a difference needs both on one server).
 */
export const createSession = (scene, colocate) =>
  request('POST', colocate ? `/api/sessions?colocate=${seg(colocate)}` : '/api/sessions',
    scene === undefined ? {} : { json: scene }).then(remember);
/** 200 {id, stats, stream_clients, scene, view_key}; 404 when the server forgot it (restart). */
export const getSession = (session) => request('GET', `/api/sessions/${seg(session)}`).then(remember);
/** The sessions the caller may read; for the teacher every one, with owner and owner_display_name. */
export const listSessions = () => request('GET', '/api/sessions').then((list) => { list.forEach(remember); return list; });
/** 204. With `keepalive` the request outlives the page (unload: sendBeacon cannot DELETE). */
export const deleteSession = (session, { keepalive = false } = {}) =>
  keepalive ? fetch(`/api/sessions/${seg(session)}`, { method: 'DELETE', keepalive: true, headers: headers() }).catch(() => {})
    : request('DELETE', `/api/sessions/${seg(session)}`);

export const getScene = (session) => request('GET', `/api/sessions/${seg(session)}/scene`);
/** RFC 7386 merge patch; arrays (objects) are replaced whole. Answers the full scene. */
export const patchScene = (session, patch) => request('PATCH', `/api/sessions/${seg(session)}/scene`, { json: patch });
/** Replaces the whole scene; answers it complete. */
export const putScene = (session, scene) => request('PUT', `/api/sessions/${seg(session)}/scene`, { json: scene });
export const getStats = (session) => request('GET', `/api/sessions/${seg(session)}/stats`);
/** rel_error against render time since the last restart, with the log-log fit (docs/api.md). */
export const getConvergence = (session, maxPoints = 400) =>
  request('GET', `/api/sessions/${seg(session)}/convergence?max_points=${maxPoints}`);

// Analysis plots: kind is polar, lobe, albedo or slice; body {series: [{brdf, params, label}], ...}.
export const analysis = (kind, body) => request('POST', `/api/analysis/${seg(kind)}`, { json: body });

/**
 * The difference of two sessions' latest frames (A - B): the PNG on its diverging colour map as
 * a Blob, with the figures its headers carry. Same errors as request() (400 while a view has no
 * error estimate yet).
 */
export async function getDifference(a, b) {
  const res = await fetch(`/api/sessions/${seg(a)}/difference?against=${seg(b)}`, { headers: headers() });
  if (!res.ok) throw await failed(res);
  const num = (h) => { const v = res.headers.get(h); return v == null ? null : Number(v); };
  return {
    image: await res.blob(),
    range: num('X-Difference-Range'),
    relRms: num('X-Rel-RMS'),
    relRmsError: num('X-Rel-RMS-Error'),
    samples: (res.headers.get('X-Samples') || '').split(',').map(Number),
  };
}

/** URL for an <img>: multipart/x-mixed-replace PNG stream. `nonce` forces a reconnect. */
export const streamUrl = (session, nonce = 0) => `/api/sessions/${seg(session)}/stream?n=${nonce}${keyParam(session)}`;
/** URL for an <img> of the session's latest frame at once (a thumbnail); `nonce` loads a newer one. */
export const frameUrl = (session, nonce = 0) => `/api/sessions/${seg(session)}/frame?min_spp=0&n=${nonce}${keyParam(session)}`;
/** URL that downloads the current frame (`png`, `pfm` or `exr`) as an attachment. */
export const frameDownloadUrl = (session, format) =>
  `/api/sessions/${seg(session)}/frame?format=${seg(format)}&min_spp=0&download=1${keyParam(session)}`;
