// Camera: two modes for the mouse (the bar under the view switches them). Orbit, the default:
// left-drag turns the camera about the selected object's centre, the wheel changes the distance
// to it (within limits). First person: left-drag looks around, the wheel changes the field of
// view. In both, W/A/S/D/Q/E move (forward, left, back, right, up, down) while the view has
// focus or nothing editable does. "Frame object" aims at the selected object from a distance at
// which it fills the view; "Reset view" asks the server for its default camera. A small form
// edits position, yaw, pitch, fov and both speeds. Changes edit the scene's `camera`
// (scene-commands.js: one request in flight, the latest value winning); the maths is
// camera-math.js.
import { state, set, on } from '../state.js';
import { editScene, editsPending } from '../scene-commands.js';
import { move, clamp, MAX_PITCH, orbit, dolly, orbitLimits, frameSphere } from '../camera-math.js';
import { boundingSphere } from '../mesh-bounds.js';

const MOVE_KEYS = new Set(['w', 'a', 's', 'd', 'q', 'e']);

const HINTS = {
  orbit: 'drag: orbit the selected object · wheel: distance · W/A/S/D/Q/E move',
  fly: 'drag: look around · wheel: field of view · W/A/S/D/Q/E move',
};

/** W/A/S/D/Q/E move the camera while held, one step each animation frame. */
function driveKeys(s) {
  let lastTick = 0;
  const editable = (t) => t instanceof HTMLElement && (t.isContentEditable || /^(INPUT|TEXTAREA|SELECT)$/.test(t.tagName));
  window.addEventListener('keydown', (ev) => {
    const k = ev.key.toLowerCase();
    if (!MOVE_KEYS.has(k) || ev.ctrlKey || ev.metaKey || ev.altKey || editable(ev.target) || !s.cam) return;
    ev.preventDefault();
    if (!s.held.size) { lastTick = performance.now(); requestAnimationFrame(tick); }
    s.held.add(k);
  });
  window.addEventListener('keyup', (ev) => s.held.delete(ev.key.toLowerCase()));
  window.addEventListener('blur', () => s.held.clear());   // a key released in another window
  function tick(now) {
    if (!s.held.size) return;
    const dt = Math.min(0.1, (now - lastTick) / 1000);   // a stalled tab must not teleport
    lastTick = now;
    s.cam.position = move(s.cam.position, s.cam.yaw, s.cam.pitch, s.held, state.speeds.move * dt);
    s.changed();
    requestAnimationFrame(tick);
  }
}

const target = () => boundingSphere(state.scene?.objects?.[state.selected]);
const aspect = () => (state.scene ? state.scene.render.width / state.scene.render.height : 1);

/** Left-drag orbits or looks, the wheel changes the distance or the field of view. */
function driveMouse(viewEl, s) {
  viewEl.addEventListener('pointerdown', (ev) => {
    if (ev.button !== 0 || !s.cam) return;
    s.dragging = true;
    viewEl.setPointerCapture(ev.pointerId);
    viewEl.focus();
  });
  viewEl.addEventListener('pointermove', (ev) => {
    if (!s.dragging || (!ev.movementX && !ev.movementY)) return;
    // Drag right: yaw decreases (+yaw turns toward -X), so first person looks right and the
    // orbit carries the camera to the left, turning the object's near side the way the mouse
    // went. Drag up: pitch increases (first person looks up; the orbit goes below the object).
    const dYaw = -ev.movementX * state.speeds.look, dPitch = -ev.movementY * state.speeds.look;
    if (s.mode === 'orbit') {
      s.cam = orbit(s.cam, target().center, dYaw, dPitch);
    } else {
      s.cam.yaw += dYaw;
      s.cam.pitch = clamp(s.cam.pitch + dPitch, -MAX_PITCH, MAX_PITCH);
    }
    s.changed();
  });
  const stop = () => { s.dragging = false; };
  viewEl.addEventListener('pointerup', stop);
  viewEl.addEventListener('pointercancel', stop);
  viewEl.addEventListener('wheel', (ev) => {
    if (!s.cam) return;
    ev.preventDefault();
    const factor = Math.exp(ev.deltaY * 0.001);   // multiplicative: even steps
    if (s.mode === 'orbit') {
      const sphere = target();
      s.cam = dolly(s.cam, sphere.center, factor, orbitLimits(sphere, s.cam.fov, aspect()));
    } else {
      s.cam.fov = clamp(s.cam.fov * factor, 5, 120);
    }
    s.changed();
  }, { passive: false });
}

/** The bar under the view: mode, Frame object, Reset view. */
function mountBar(barEl, viewEl, s) {
  const modeButtons = [...barEl.querySelectorAll('[data-mode]')];
  const showMode = () => {
    for (const b of modeButtons) b.setAttribute('aria-pressed', String(b.dataset.mode === s.mode));
    viewEl.title = HINTS[s.mode];
  };
  for (const b of modeButtons) b.addEventListener('click', () => { s.mode = b.dataset.mode; showMode(); });
  showMode();
  barEl.querySelector('.view-frame').addEventListener('click', () => {
    if (!s.cam || !state.scene?.objects?.length) return;
    s.cam = frameSphere(s.cam, target(), aspect());
    s.changed();
  });
  barEl.querySelector('.view-reset').addEventListener('click', s.reset);
}

/** The form: position, yaw, pitch, fov and both speeds. Returns showForm(). */
function mountForm(formEl, s) {
  const input = (name) => formEl.querySelector(`[name="${name}"]`);
  const fields = { px: ['position', 0], py: ['position', 1], pz: ['position', 2], yaw: ['yaw'], pitch: ['pitch'], fov: ['fov'] };
  function showForm() {
    if (!s.cam) return;
    for (const [name, [key, i]] of Object.entries(fields)) {
      const el = input(name);
      if (document.activeElement === el) continue;   // never overwrite what the user types
      const v = i === undefined ? s.cam[key] : s.cam[key][i];
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
    if (!key || !s.cam) return;
    if (i === undefined) s.cam[key] = v; else s.cam[key][i] = v;
    if (key === 'pitch') s.cam.pitch = clamp(s.cam.pitch, -MAX_PITCH, MAX_PITCH);
    if (key === 'fov') s.cam.fov = clamp(s.cam.fov, 1.01, 178.99);
    s.changed();
  });
  formEl.addEventListener('submit', (ev) => ev.preventDefault());
  input('move').value = state.speeds.move;
  input('look').value = state.speeds.look;
  return showForm;
}

export function mountCamera(viewEl, formEl, barEl) {
  // What the sub-views share: `cam`, our copy of the camera (the source of truth while the
  // user drives it), the mouse mode ('orbit' | 'fly', first person), the keys held, a drag.
  const s = { cam: null, mode: 'orbit', held: new Set(), dragging: false };
  const showForm = mountForm(formEl, s);
  const failed = (e) => set({ status: `camera: ${e.message}` });
  s.changed = () => {
    editScene({ camera: { ...s.cam, position: s.cam.position.slice() } }).catch(failed);
    showForm();
  };
  // `null` resets: a merge patch that removes `camera` gives the scene its default camera,
  // which only the server knows: not shown before its answer.
  s.reset = () => editScene({ camera: null }, { optimistic: false })
    .then((scene) => { s.cam = structuredClone(scene.camera); showForm(); }, failed);

  // Adopt the server's camera only when we are not driving it: a reply to an older PATCH
  // must not pull the camera back while keys are held or a drag is on.
  on('scene', ({ scene }) => {
    if (!scene?.camera) return;
    if (s.cam && (s.held.size || s.dragging || editsPending())) return;
    s.cam = structuredClone(scene.camera);
    showForm();
  });

  driveKeys(s);
  driveMouse(viewEl, s);
  mountBar(barEl, viewEl, s);
}
