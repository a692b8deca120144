// Camera: W/A/S/D/Q/E move (forward, left, back, right, up, down) while the view has focus or
// nothing editable does; left-drag on the view looks around; the wheel changes the field of
// view; a small form edits position, yaw, pitch, fov and both speeds. Changes PATCH the scene's
// `camera` (one request in flight, latest value wins: coalesce.js).
import * as api from '../api.js';
import { state, set, on } from '../state.js';
import { coalesce } from '../coalesce.js';
import { move, clamp, MAX_PITCH } from '../camera-math.js';

const MOVE_KEYS = new Set(['w', 'a', 's', 'd', 'q', 'e']);

export function mountCamera(viewEl, formEl) {
  let cam = null;               // our copy; the source of truth while the user drives it
  const held = new Set();
  let lastTick = 0;
  let dragging = false;

  const send = coalesce(async (camera) => {
    try {
      set({ scene: await api.patchScene(state.session, { camera }) });
    } catch (e) {
      set({ status: `camera: ${e.message}` });
    }
  });
  const changed = () => {
    send({ ...cam, position: cam.position.slice() });
    showForm();
  };

  // Adopt the server's camera only when we are not driving it: a reply to an older PATCH
  // must not pull the camera back while keys are held or a drag is on.
  on('scene', ({ scene }) => {
    if (!scene?.camera) return;
    if (cam && (held.size || dragging || !send.idle())) return;
    cam = structuredClone(scene.camera);
    showForm();
  });

  // ---- keys ----
  const editable = (t) => t instanceof HTMLElement && (t.isContentEditable || /^(INPUT|TEXTAREA|SELECT)$/.test(t.tagName));
  window.addEventListener('keydown', (ev) => {
    const k = ev.key.toLowerCase();
    if (!MOVE_KEYS.has(k) || ev.ctrlKey || ev.metaKey || ev.altKey || editable(ev.target) || !cam) return;
    ev.preventDefault();
    if (!held.size) { lastTick = performance.now(); requestAnimationFrame(tick); }
    held.add(k);
  });
  window.addEventListener('keyup', (ev) => held.delete(ev.key.toLowerCase()));
  window.addEventListener('blur', () => held.clear());   // a key released in another window
  function tick(now) {
    if (!held.size) return;
    const dt = Math.min(0.1, (now - lastTick) / 1000);   // a stalled tab must not teleport
    lastTick = now;
    cam.position = move(cam.position, cam.yaw, cam.pitch, held, state.speeds.move * dt);
    changed();
    requestAnimationFrame(tick);
  }

  // ---- mouse: left-drag looks, wheel zooms ----
  viewEl.addEventListener('pointerdown', (ev) => {
    if (ev.button !== 0 || !cam) return;
    dragging = true;
    viewEl.setPointerCapture(ev.pointerId);
    viewEl.focus();
  });
  viewEl.addEventListener('pointermove', (ev) => {
    if (!dragging || (!ev.movementX && !ev.movementY)) return;
    // Drag right looks right (yaw decreases: +yaw turns toward -X); drag up looks up.
    cam.yaw -= ev.movementX * state.speeds.look;
    cam.pitch = clamp(cam.pitch - ev.movementY * state.speeds.look, -MAX_PITCH, MAX_PITCH);
    changed();
  });
  const stop = () => { dragging = false; };
  viewEl.addEventListener('pointerup', stop);
  viewEl.addEventListener('pointercancel', stop);
  viewEl.addEventListener('wheel', (ev) => {
    if (!cam) return;
    ev.preventDefault();
    cam.fov = clamp(cam.fov * Math.exp(ev.deltaY * 0.001), 5, 120);   // multiplicative: even steps
    changed();
  }, { passive: false });

  // ---- form ----
  const input = (name) => formEl.querySelector(`[name="${name}"]`);
  const fields = { px: ['position', 0], py: ['position', 1], pz: ['position', 2], yaw: ['yaw'], pitch: ['pitch'], fov: ['fov'] };
  function showForm() {
    if (!cam) return;
    for (const [name, [key, i]] of Object.entries(fields)) {
      const el = input(name);
      if (document.activeElement === el) continue;   // never overwrite what the user types
      const v = i === undefined ? cam[key] : cam[key][i];
      el.value = Number(v.toFixed(3));
    }
  }
  formEl.addEventListener('change', (ev) => {
    const el = ev.target;
    const v = Number(el.value);
    if (!Number.isFinite(v)) return;
    if (el.name === 'move' || el.name === 'look') {
      set({ speeds: { ...state.speeds, [el.name]: v } });
      return;
    }
    const [key, i] = fields[el.name] || [];
    if (!key || !cam) return;
    if (i === undefined) cam[key] = v; else cam[key][i] = v;
    if (key === 'pitch') cam.pitch = clamp(cam.pitch, -MAX_PITCH, MAX_PITCH);
    if (key === 'fov') cam.fov = clamp(cam.fov, 1.01, 178.99);
    changed();
  });
  formEl.addEventListener('submit', (ev) => ev.preventDefault());
  input('move').value = state.speeds.move;
  input('look').value = state.speeds.look;
}
