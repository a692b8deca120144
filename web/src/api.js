// The one module that talks to the network (DESIGN.md section 7). Everything else calls these
// functions and never builds a URL or calls fetch itself. Endpoints: docs/api.md.

/** An HTTP error with the server's JSON body ({error, message, field?, diagnostics?}). */
export class ApiError extends Error {
  constructor(status, body) {
    super((body && body.message) || `HTTP ${status}`);
    this.status = status;
    this.body = body || {};
  }
}

async function request(method, path, { json, text, form } = {}) {
  const init = { method, headers: {} };
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
  if (!res.ok) throw await apiError(res);
  return readBody(res);
}

const readBody = (res) => ((res.headers.get('Content-Type') || '').includes('application/json') ? res.json() : res.text());

async function apiError(res) {
  const body = await readBody(res);
  return new ApiError(res.status, typeof body === 'object' ? body : { message: body });
}

const seg = encodeURIComponent;

export const health = () => request('GET', '/api/health');

export const listBrdfs = () => request('GET', '/api/brdfs');
export const getBrdf = (name) => request('GET', `/api/brdfs/${seg(name)}`);
export const validateBrdf = (source) => request('POST', '/api/brdfs/validate', { text: source });
/** Compiles and stores; 422 with `diagnostics` on a compile error (nothing stored then). */
export const putBrdf = (name, source) => request('PUT', `/api/brdfs/${seg(name)}`, { text: source });
/** 204; 409 for a built-in. Removes the BRDF's presets too. */
export const deleteBrdf = (name) => request('DELETE', `/api/brdfs/${seg(name)}`);

// Presets: named parameter sets of one BRDF.
export const listPresets = (brdf) => request('GET', `/api/brdfs/${seg(brdf)}/presets`);
export const getPreset = (brdf, preset) => request('GET', `/api/brdfs/${seg(brdf)}/presets/${seg(preset)}`);
export const putPreset = (brdf, preset, values) => request('PUT', `/api/brdfs/${seg(brdf)}/presets/${seg(preset)}`, { json: values });
export const deletePreset = (brdf, preset) => request('DELETE', `/api/brdfs/${seg(brdf)}/presets/${seg(preset)}`);

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

/**
 * 201 {id, scene}. `scene` is optional (all defaults). `colocate`: a session the new one must
 * live beside (behind the replicas' balancer, docs/deploy.md: a difference needs both on one server).
 */
export const createSession = (scene, colocate) =>
  request('POST', colocate ? `/api/sessions?colocate=${seg(colocate)}` : '/api/sessions',
    scene === undefined ? {} : { json: scene });
/** 200 {id, stats, stream_clients, scene}; 404 when the server forgot it (restart). */
export const getSession = (session) => request('GET', `/api/sessions/${seg(session)}`);
/** 204. With `keepalive` the request outlives the page (unload: sendBeacon cannot DELETE). */
export const deleteSession = (session, { keepalive = false } = {}) =>
  keepalive ? fetch(`/api/sessions/${seg(session)}`, { method: 'DELETE', keepalive: true }).catch(() => {})
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
  const res = await fetch(`/api/sessions/${seg(a)}/difference?against=${seg(b)}`);
  if (!res.ok) throw await apiError(res);
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
export const streamUrl = (session, nonce = 0) => `/api/sessions/${seg(session)}/stream?n=${nonce}`;
/** URL that downloads the current frame (`png`, `pfm` or `exr`) as an attachment. */
export const frameDownloadUrl = (session, format) =>
  `/api/sessions/${seg(session)}/frame?format=${seg(format)}&min_spp=0&download=1`;
