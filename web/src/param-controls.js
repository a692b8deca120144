// Controls for a parameter set that is not the scene's: an analysis series, or the B side of a
// comparison. One row per declaration (slider, colour picker or check box) with its value;
// every `input` event calls onChange(values) with the whole set, so a drag updates live.
import { toHex, fromHex } from './color.js';

/** The file's defaults: {name: default} for the declarations [{name, type, min, max, default}]. */
export const defaults = (decls) => Object.fromEntries((decls || []).map((d) => [d.name, d.default]));

export function paramControls(host, decls, values, onChange) {
  const current = { ...defaults(decls), ...values };
  const rows = (decls || []).map((d) => {
    const row = document.createElement('label');
    row.className = 'param';
    const name = document.createElement('span');
    name.textContent = d.name;
    const input = document.createElement('input');
    input.name = d.name;
    input.type = d.type === 'float' ? 'range' : d.type === 'color' ? 'color' : 'checkbox';
    if (d.type === 'float') Object.assign(input, { min: d.min, max: d.max, step: (d.max - d.min) / 1000 || 'any' });
    const out = document.createElement('output');
    const show = (v) => {
      if (d.type === 'color') input.value = toHex(v);
      else if (d.type === 'bool') input.checked = !!v;
      else input.value = v;
      out.textContent = d.type === 'float' ? Number(v).toPrecision(3) : '';
    };
    show(current[d.name]);
    input.addEventListener('input', () => {
      current[d.name] = d.type === 'color' ? fromHex(input.value) : d.type === 'bool' ? input.checked : Number(input.value);
      show(current[d.name]);
      onChange({ ...current });
    });
    row.append(name, input, out);
    return row;
  });
  host.replaceChildren(...rows);
  if (!rows.length) host.textContent = 'no parameters';
}
