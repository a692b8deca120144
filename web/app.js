// Minimal UI: live stream, stats, and a BRDF editor. Panels never call each other: they read
// and change one state object and listen to its events (three.js editor style); api.js alone
// talks to the network.
import * as api from './api.js';

// ---- state -------------------------------------------------------------------------------
const state = {
  session: 'default',
  scene: null,        // the session's full scene JSON
  stats: null,        // latest /stats reply
  source: '',         // editor text
  diagnostics: [],    // [{line, column, severity, message}]
  status: '',         // one line for the user
};
const listeners = new Map();
function on(event, fn) {
  if (!listeners.has(event)) listeners.set(event, []);
  listeners.get(event).push(fn);
}
function set(changes) {
  Object.assign(state, changes);
  for (const key of Object.keys(changes)) for (const fn of listeners.get(key) || []) fn(state);
}

// ---- viewer panel ------------------------------------------------------------------------
{
  const img = document.getElementById('view');
  let nonce = 0;
  const connect = () => { img.src = api.streamUrl(state.session, nonce++); };
  // A dropped stream (server restart, network) reconnects after a pause.
  img.addEventListener('error', () => setTimeout(connect, 1000));
  connect();
}

// ---- stats panel -------------------------------------------------------------------------
{
  const el = document.getElementById('stats');
  on('stats', ({ stats }) => {
    if (!stats) return;
    const err = stats.rel_error == null ? 'n/a' : `${(stats.rel_error * 100).toFixed(2)}%`;
    el.textContent = `spp ${stats.spp}  ·  rel. error ${err}  ·  ${stats.ms_per_frame.toFixed(1)} ms/frame` +
      (stats.nan_samples ? `  ·  NaN samples ${stats.nan_samples}` : '') + (stats.converged ? '  ·  converged' : '');
  });
  const poll = async () => {
    try { set({ stats: await api.getStats(state.session) }); } catch (e) { set({ status: `stats: ${e.message}` }); }
  };
  setInterval(poll, 1000);
  poll();
}

// ---- editor panel ------------------------------------------------------------------------
{
  const text = document.getElementById('source');
  const button = document.getElementById('compile');
  const list = document.getElementById('diagnostics');
  const status = document.getElementById('status');

  text.addEventListener('input', () => set({ source: text.value }));
  on('source', ({ source }) => { if (text.value !== source) text.value = source; });
  on('status', ({ status: s }) => { status.textContent = s; });
  on('diagnostics', ({ diagnostics }) => {
    list.replaceChildren(...diagnostics.map((d) => {
      const li = document.createElement('li');
      li.className = d.severity;
      li.textContent = `${d.line > 0 ? `line ${d.line}` : 'generated code'}: ${d.message}`;
      return li;
    }));
  });

  button.addEventListener('click', async () => {
    button.disabled = true;
    set({ status: 'compiling…', diagnostics: [] });
    try {
      const report = await api.validateBrdf(state.source);
      set({ diagnostics: report.warnings || [] });
      await api.putBrdf('scratch', state.source);
      // objects is an array: a merge patch replaces it whole. Drop the old BRDF's params,
      // which the new one may not have.
      const objects = (state.scene?.objects || [{}]).map((o, i) => (i === 0 ? { ...o, brdf: 'scratch', params: {} } : o));
      set({ scene: await api.patchScene(state.session, { objects }),
            status: `compiled in ${report.compile_ms.toFixed(1)} ms` });
    } catch (e) {
      set({ diagnostics: e.body?.diagnostics || [], status: `${e.status || ''} ${e.message}` });
    } finally {
      button.disabled = false;
    }
  });
}

// ---- start -------------------------------------------------------------------------------
(async () => {
  try {
    const scene = await api.getScene(state.session);
    set({ scene });
    const brdf = await api.getBrdf(scene.objects?.[0]?.brdf || 'ggx');
    set({ source: brdf.source, status: `editing a copy of "${brdf.name}"` });
  } catch (e) {
    set({ status: `load failed: ${e.message}` });
  }
})();
