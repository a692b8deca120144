// Environment: choose a built-in, Blender world or uploaded environment, or upload one (HDR,
// EXR, or a PNG/JPEG horizontal cross); intensity, rotation about +Y, visible as background.
import * as api from '../api.js';
import { state, on } from '../state.js';
import { editScene } from '../scene-commands.js';
import { refreshAssets } from '../library.js';

export function mountEnvironment(el) {
  const $ = (c) => el.querySelector(c);
  const status = $('.env-status');
  // Each control edits only its own field: while one PATCH is in flight, the others' changes
  // compose with it (scene-commands.js), so none is lost on a slow server, and the local scene
  // holds them at once: a reply to an earlier PATCH does not put an old value back.
  const send = (fields) => editScene({ environment: fields })
    .then(() => { status.textContent = ''; }, (e) => { status.textContent = e.message; });
  const focused = (x) => document.activeElement === x;

  function show() {
    const env = state.scene?.environment;
    if (!env) return;
    const names = (state.assets || []).filter((a) => a.kind === 'environment');
    const sel = $('.env-name');
    if (!focused(sel)) {
      const opts = names.map((a) => { const o = document.createElement('option'); o.value = a.id; o.textContent = a.builtin ? a.id : `${a.name} (${a.id})`; return o; });
      if (!names.some((a) => a.id === env.name)) { const o = document.createElement('option'); o.value = o.textContent = env.name; opts.push(o); }
      sel.replaceChildren(...opts);
      sel.value = env.name;
    }
    if (!focused($('.env-intensity'))) $('.env-intensity').value = env.intensity;
    if (!focused($('.env-rotation'))) $('.env-rotation').value = env.rotation;
    $('.env-visible').checked = env.visible;
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
