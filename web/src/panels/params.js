// Parameters: sliders, colour pickers and check boxes built from the declarations of the BRDF
// that the selected object uses (state.brdf.params; state.selected, chosen in the Objects tab).
// Moving one edits objects[selected].params (scene-commands.js): the server applies
// value-only changes without recompiling, so the frame updates within a pass.
import * as api from '../api.js';
import { state, set, on } from '../state.js';
import { editScene } from '../scene-commands.js';
import { toHex, fromHex } from '../color.js';
import { NAME_RE, isScratch } from '../library.js';

/** The value a control holds, as the scene stores it. */
const readValue = (decl, input) => {
  if (decl.type === 'color') return fromHex(input.value);
  if (decl.type === 'bool') return input.checked;
  return Number(input.value);
};
/** Shows `v` in control `c` ({decl, input, readout}); undefined leaves it as it is. */
const showValue = (c, v) => {
  if (v === undefined) return;
  if (c.decl.type === 'color') c.input.value = toHex(v);
  else if (c.decl.type === 'bool') c.input.checked = !!v;
  else c.input.value = v;
  c.readout.textContent = c.decl.type === 'float' ? Number(v).toPrecision(3) : '';
};

/** The selected object's parameter values (a copy). */
const current = () => ({ ...(state.scene?.objects?.[state.selected]?.params || {}) });

// `objects` is an array: a merge patch replaces it whole, so the edit holds every object.
// The local scene takes it at once, so a second control's edit carries this value too.
function apply(params) {
  const index = state.selected;
  editScene((scene) => (scene.objects[index] ? { objects: scene.objects.map((o, i) => (i === index ? { ...o, params } : o)) } : null))
    .catch((e) => set({ status: `parameters: ${e.message}` }));
}

/** One row: name, input, readout and a reset button; returns its control. */
function paramRow(list, decl) {
  const row = document.createElement('label');
  row.className = 'param';
  const name = document.createElement('span');
  name.className = 'param-name';
  name.textContent = decl.name;
  name.title = decl.name;   // the whole name, where a narrow panel cuts it short
  const input = document.createElement('input');
  input.name = decl.name;
  if (decl.type === 'float') {
    input.type = 'range';
    input.min = decl.min;
    input.max = decl.max;
    input.step = (decl.max - decl.min) / 1000 || 'any';
  } else {
    input.type = decl.type === 'color' ? 'color' : 'checkbox';
  }
  const readout = document.createElement('output');
  const reset = document.createElement('button');
  reset.type = 'button';
  reset.className = 'param-reset';
  reset.textContent = '↺';
  reset.title = `reset ${decl.name} to its default`;
  // The glyph alone is no name for a screen reader: say what it resets.
  reset.setAttribute('aria-label', reset.title);
  row.append(name, input, readout, reset);
  list.append(row);
  const c = { decl, input, readout };
  reset.addEventListener('click', (ev) => {
    ev.preventDefault();   // inside the <label>: must not toggle a check box
    showValue(c, decl.default);
    apply({ ...current(), [decl.name]: decl.default });
  });
  input.addEventListener('input', () => {
    const v = readValue(decl, input);
    showValue(c, v);
    apply({ ...current(), [decl.name]: v });
  });
  return c;
}

/** Presets: named value sets of this BRDF (stored on the server). Returns loadPresets(select). */
function mountPresets(el, controls) {
  const presetList = el.querySelector('.preset-list');
  const presetBox = el.querySelector('.presets');
  async function loadPresets(select = '') {
    const name = state.brdf?.name;
    presetBox.hidden = !name || isScratch(name);   // a scratch BRDF is per tab: save it first
    if (presetBox.hidden) return;
    try {
      const names = await api.listPresets(name);
      const opts = ['', ...names].map((n) => {
        const o = document.createElement('option');
        o.value = n;
        o.textContent = n || '(none)';
        return o;
      });
      presetList.replaceChildren(...opts);
      presetList.value = select;
    } catch (e) {
      set({ status: `presets: ${e.message}` });
    }
  }
  el.querySelector('.preset-load').addEventListener('click', async () => {
    const p = presetList.value;
    if (!p) return;
    try {
      const values = await api.getPreset(state.brdf.name, p);
      const params = current();
      for (const [k, v] of Object.entries(values)) if (controls.has(k)) { params[k] = v; showValue(controls.get(k), v); }
      apply(params);
      set({ status: `preset "${p}" loaded` });
    } catch (e) {
      set({ status: `preset: ${e.message}` });
    }
  });
  el.querySelector('.preset-save').addEventListener('click', async () => {
    const p = prompt('Preset name (letters, digits, _ and -, at most 64):', presetList.value || 'preset1');
    if (p == null) return;
    if (!NAME_RE.test(p)) { set({ status: `"${p}" is not a valid preset name` }); return; }
    const values = {};
    for (const name of controls.keys()) values[name] = current()[name];
    try {
      await api.putPreset(state.brdf.name, p, values);
      await loadPresets(p);
      set({ status: `preset "${p}" saved` });
    } catch (e) {
      set({ status: `preset: ${e.message}` });
    }
  });
  el.querySelector('.preset-delete').addEventListener('click', async () => {
    const p = presetList.value;
    if (!p || !confirm(`Delete preset "${p}"?`)) return;
    try {
      await api.deletePreset(state.brdf.name, p);
      await loadPresets();
    } catch (e) {
      set({ status: `preset: ${e.message}` });
    }
  });
  return loadPresets;
}

/** The title (which object), and what the server clamped, said beside the sliders. */
function mountHead(el) {
  const title = el.querySelector('.params-head strong');
  const showTitle = () => {
    const n = state.scene?.objects?.length || 0;
    title.textContent = n > 1 ? `Parameters (object ${state.selected + 1} of ${n})` : 'Parameters';
  };
  on('selected', showTitle);
  on('scene', showTitle);
  // What the server clamped (a value carried over from another BRDF by name, outside this
  // one's range): said beside the sliders, which show the value it renders with.
  const notes = el.querySelector('.params-notes');
  on('scene', ({ scene }) => {
    const lines = scene?.notes || [];
    notes.textContent = lines.join('\n');
    notes.hidden = !lines.length;
  });
}

export function mountParams(el) {
  const list = el.querySelector('.params-list');
  const controls = new Map();   // param name -> {decl, input, readout}

  function build({ brdf }) {
    controls.clear();
    list.replaceChildren();
    for (const decl of brdf?.params || []) {
      const c = paramRow(list, decl);
      controls.set(decl.name, c);
      showValue(c, current()[decl.name] ?? decl.default);
    }
    list.hidden = !controls.size;
  }

  const loadPresets = mountPresets(el, controls);
  on('brdf', (s) => { build(s); loadPresets(); });
  mountHead(el);
  // Values of the local scene (this panel's own edits, another control, a reload): update
  // controls not being used.
  on('scene', ({ scene }) => {
    const params = scene?.objects?.[state.selected]?.params || {};
    for (const [name, c] of controls) if (document.activeElement !== c.input) showValue(c, params[name]);
  });

  el.querySelector('.params-reset').addEventListener('click', () => {
    const params = {};
    for (const [name, c] of controls) { params[name] = c.decl.default; showValue(c, c.decl.default); }
    apply(params);
  });
}
