// Parameters: sliders, colour pickers and check boxes built from the declarations of the BRDF
// that objects[0] uses (state.brdf.params). Moving one PATCHes objects[0].params: the server
// applies value-only changes without recompiling, so the frame updates within a pass.
import * as api from '../api.js';
import { state, set, on } from '../state.js';
import { coalesce } from '../coalesce.js';
import { toHex, fromHex } from '../color.js';

const OBJECT = 0;   // the object this panel edits (the object editor will choose it later)

export function mountParams(el) {
  const list = el.querySelector('.params-list');
  const controls = new Map();   // param name -> {decl, input, readout}

  // `objects` is an array: a merge patch replaces it whole, so send every object.
  const send = coalesce(async (params) => {
    const objects = state.scene.objects.map((o, i) => (i === OBJECT ? { ...o, params } : o));
    try {
      set({ scene: await api.patchScene(state.session, { objects }) });
    } catch (e) {
      set({ status: `parameters: ${e.message}` });
    }
  });
  const current = () => ({ ...(state.scene?.objects?.[OBJECT]?.params || {}) });

  const readValue = (decl, input) => {
    if (decl.type === 'color') return fromHex(input.value);
    if (decl.type === 'bool') return input.checked;
    return Number(input.value);
  };
  const showValue = (c, v) => {
    if (v === undefined) return;
    if (c.decl.type === 'color') c.input.value = toHex(v);
    else if (c.decl.type === 'bool') c.input.checked = !!v;
    else c.input.value = v;
    c.readout.textContent = c.decl.type === 'float' ? Number(v).toPrecision(3) : '';
  };

  function build({ brdf }) {
    controls.clear();
    list.replaceChildren();
    for (const decl of brdf?.params || []) {
      const row = document.createElement('label');
      row.className = 'param';
      const name = document.createElement('span');
      name.textContent = decl.name;
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
      row.append(name, input, readout);
      list.append(row);
      const c = { decl, input, readout };
      controls.set(decl.name, c);
      showValue(c, current()[decl.name] ?? decl.default);
      input.addEventListener('input', () => {
        const v = readValue(decl, input);
        showValue(c, v);
        const params = current();
        params[decl.name] = v;
        // Keep the local scene in step so a second control's patch carries this value too.
        state.scene.objects[OBJECT].params = params;
        send(params);
      });
    }
    list.hidden = !controls.size;
  }

  on('brdf', build);
  // Values the server answered (another control, a reload): update controls not being used.
  on('scene', ({ scene }) => {
    const params = scene?.objects?.[OBJECT]?.params || {};
    for (const [name, c] of controls) if (document.activeElement !== c.input) showValue(c, params[name]);
  });

  el.querySelector('.params-reset').addEventListener('click', () => {
    const params = {};
    for (const [name, c] of controls) { params[name] = c.decl.default; showValue(c, c.decl.default); }
    state.scene.objects[OBJECT].params = params;
    send(params);
  });
}
