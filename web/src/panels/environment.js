// Environment: choose a built-in, Blender world or uploaded environment, or upload one (HDR,
// EXR, or a PNG/JPEG horizontal cross); intensity, rotation about +Y, visible as background.
import * as api from '../api.js';
import { state, set, on } from '../state.js';
import { coalesce } from '../coalesce.js';
import { refreshAssets } from '../library.js';

export function mountEnvironment(el) {
  const $ = (c) => el.querySelector(c);
  const status = $('.env-status');
  // Each control sends only its own field: while one PATCH is in flight, the others' changes
  // merge (a newer value of the same field wins), so none is lost on a slow server.
  // Fields changed here and not yet answered: a scene that arrives meanwhile (the reply to an
  // earlier PATCH, a camera move) must not put the old value back into their controls.
  const pending = {};
  const patch = coalesce(async (environment) => {
    try {
      set({ scene: await api.patchScene(state.session, { environment }) });
      status.textContent = '';
    } catch (e) {
      status.textContent = e.message;
    } finally {
      for (const [k, v] of Object.entries(environment)) if (pending[k] === v) delete pending[k];
      if (shown()) show();
    }
  }, (older, newer) => ({ ...older, ...newer }));
  const send = (fields) => {
    Object.assign(pending, fields);
    patch(fields);
  };
  const focused = (x) => document.activeElement === x;

  function show() {
    const env = state.scene?.environment;
    if (!env) return;
    const names = (state.assets || []).filter((a) => a.kind === 'environment');
    const sel = $('.env-name');
    if (!focused(sel) && !('name' in pending)) {
      const opts = names.map((a) => { const o = document.createElement('option'); o.value = a.id; o.textContent = a.builtin ? a.id : `${a.name} (${a.id})`; return o; });
      if (!names.some((a) => a.id === env.name)) { const o = document.createElement('option'); o.value = o.textContent = env.name; opts.push(o); }
      sel.replaceChildren(...opts);
      sel.value = env.name;
    }
    if (!focused($('.env-intensity')) && !('intensity' in pending)) $('.env-intensity').value = env.intensity;
    if (!focused($('.env-rotation')) && !('rotation' in pending)) $('.env-rotation').value = env.rotation;
    if (!('visible' in pending)) $('.env-visible').checked = env.visible;
  }
  // Rebuilt only while its tab is shown: a camera drag answers a scene many times a second.
  const shown = () => !el.closest('.tab-page')?.hidden;
  on('scene', () => shown() && show());
  on('assets', () => shown() && show());
  on('tab', () => shown() && show());

  $('.env-name').addEventListener('change', (ev) => send({ name: ev.target.value }));
  const number = (cls, key, ok) => $(cls).addEventListener('change', (ev) => {
    const v = Number(ev.target.value);
    if (ev.target.value !== '' && Number.isFinite(v) && ok(v)) send({ [key]: v });
  });
  number('.env-intensity', 'intensity', (v) => v >= 0 && v <= 1e6);
  number('.env-rotation', 'rotation', (v) => Math.abs(v) <= 1e6);
  $('.env-visible').addEventListener('change', (ev) => send({ visible: ev.target.checked }));
  $('.env-upload').addEventListener('change', async (ev) => {
    const file = ev.target.files?.[0];
    if (!file) return;
    status.textContent = `uploading ${file.name}…`;
    try {
      const asset = await api.uploadAsset(file, 'environment');
      await refreshAssets();
      send({ name: asset.id });
      status.textContent = `uploaded ${asset.name} as ${asset.id}`;
    } catch (e) {
      status.textContent = `upload: ${e.message}`;
    } finally {
      ev.target.value = '';
    }
  });
}
