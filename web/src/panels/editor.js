// BRDF editor: CodeMirror 6 with GLSL highlighting (the `shader` mode of
// @codemirror/legacy-modes' clike family: GLSL keywords, types and built-ins; the .brdf
// `::begin` lines are plain text to it). Compiles on Ctrl+Enter and after a pause in typing;
// the server's 422 diagnostics become lint markers in the gutter and messages on their lines.
// A successful compile is stored as this session's scratch BRDF and the selected object
// (state.selected, objects[0] unless the Objects tab chose another) switches to it.
import { EditorView, basicSetup } from 'codemirror';
import { keymap } from '@codemirror/view';
import { Prec, Transaction } from '@codemirror/state';
import { StreamLanguage } from '@codemirror/language';
import { shader } from '@codemirror/legacy-modes/mode/clike';
import { setDiagnostics, lintGutter } from '@codemirror/lint';
import * as api from '../api.js';
import { state, set, on } from '../state.js';
import { editScene, reloadScene } from '../scene-commands.js';
import { refreshLibrary, NAME_RE, bareName, namespace, ownName, canWrite, canDelete } from '../library.js';

const IDLE_MS = 800;   // a pause in typing this long compiles

// A per-session name so tabs never overwrite each other's work (names: [A-Za-z0-9_-]{1,64}),
// under the person's namespace (`alice/scratch-<session>`; bare for the teacher).
export const scratchName = (session) => `${namespace()}scratch-${session}`;

/** Server diagnostic (1-based line, 1-based column or 0) -> CodeMirror diagnostic. */
function toCm(doc, d) {
  const n = Math.min(Math.max(d.line || 1, 1), doc.lines);
  const line = doc.line(n);
  const from = d.column > 0 ? Math.min(line.from + d.column - 1, line.to) : line.from;
  return {
    from,
    to: Math.max(from, line.to),
    severity: d.severity === 'warning' ? 'warning' : 'error',
    // line 0: not attributable to the user's text (generated code); shown on line 1.
    message: d.line > 0 ? d.message : `(generated code) ${d.message}`,
  };
}

// Values that still fit after a recompile are kept; the server fills in the rest with defaults.
function keptParams(old, decls) {
  const fits = { float: (v) => typeof v === 'number', color: Array.isArray, bool: (v) => typeof v === 'boolean' };
  const out = {};
  for (const d of decls) if (old && old[d.name] !== undefined && fits[d.type]?.(old[d.name])) out[d.name] = old[d.name];
  return out;
}

/** The selected object renders `name`, keeping the values that still fit; resolves once the server answered. */
function switchObject(name, decls) {
  const sel = state.selected;
  return editScene((scene) => ({
    objects: scene.objects.map((o, i) => (i === sel ? { ...o, brdf: name, params: keptParams(o.params, decls) } : o)),
  }));
}

// What New starts from: one parameter of each kind and a Lambert + Blinn-Phong lobe.
export const TEMPLATE = `analytic
# my_brdf: describe the model and cite its source here.

::begin parameters
color albedo 0.8 0.8 0.8   # diffuse colour
float shininess 1 500 40   # highlight exponent
float ks 0 1 0.2           # highlight strength
bool highlight 1           # draw the highlight
::end parameters

::begin shader
const float PI = 3.14159265358979323846;

vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    if (dot(N, L) <= 0.0 || dot(N, V) <= 0.0) return vec3(0.0);
    vec3 f = albedo / PI;
    if (highlight) {
        vec3 H = normalize(L + V);
        f += vec3(ks * (shininess + 8.0) / (8.0 * PI) * pow(max(dot(N, H), 0.0), shininess));
    }
    return f;
}
::end shader
`;

/** The CodeMirror view: GLSL highlighting, lint gutter, Ctrl+Enter and a pause in typing compile. */
function createView(el, ed) {
  let idle = 0;
  ed.stopIdle = () => clearTimeout(idle);
  return new EditorView({
    parent: el.querySelector('.editor-host'),
    extensions: [
      basicSetup,
      StreamLanguage.define(shader),
      lintGutter(),
      Prec.highest(keymap.of([{ key: 'Mod-Enter', run: () => { ed.compile(); return true; } }])),
      EditorView.updateListener.of((u) => {
        // Only the user's edits start the idle timer, not loading a BRDF's source.
        if (u.docChanged) queueMicrotask(ed.showLibrary);   // the "unsaved changes" mark
        if (!u.docChanged || !u.transactions.some((tr) => tr.annotation(Transaction.userEvent))) return;
        clearTimeout(idle);
        idle = setTimeout(ed.compile, IDLE_MS);
      }),
    ],
  });
}

/** compile(): the text into this tab's scratch BRDF, which the selected object then renders. */
function makeCompile(ed) {
  let busy = false;
  let again = false;
  return async function compile() {
    ed.stopIdle();
    if (!state.session || !state.scene) return;
    if (busy) { again = true; return; }   // one compile at a time; the newest text runs next
    busy = true;
    const source = ed.text();
    const name = scratchName(state.session);
    set({ status: 'compiling…' });
    try {
      const brdf = await api.putBrdf(name, source);
      await switchObject(name, brdf.params);
      ed.stored = source;
      set({ brdf: { name, params: brdf.params }, diagnostics: brdf.warnings || [],
            status: brdf.cached ? 'compiled (cached)' : `compiled in ${brdf.compile_ms.toFixed(0)} ms` });
    } catch (e) {
      const diagnostics = e.body?.diagnostics || [];
      set({ diagnostics, status: e.status === 422 ? `${diagnostics.length} compile error(s)` : `compile: ${e.message}` });
    } finally {
      busy = false;
      if (again) { again = false; compile(); }
    }
  };
}

/** Compile diagnostics as lint markers and as a list; the status line. */
function mountDiagnostics(el, view) {
  const list = el.querySelector('.diagnostics');
  const status = el.querySelector('.status');
  on('diagnostics', ({ diagnostics }) => {
    const doc = view.state.doc;
    view.dispatch(setDiagnostics(view.state, diagnostics.map((d) => toCm(doc, d))));
    list.replaceChildren(...diagnostics.map((d) => {
      const li = document.createElement('li');
      li.className = d.severity;
      li.textContent = `${d.line > 0 ? `line ${d.line}` : 'generated code'}: ${d.message}`;
      return li;
    }));
  });
  on('status', ({ status: s }) => { status.textContent = s; });
}

/** The library list, and what Save and Delete may do for the text the editor holds. */
function makeShowLibrary(ed) {
  const { $ } = ed;
  return function showLibrary() {
    const cur = state.editing?.name;
    const opts = state.library.map((b) => {
      const o = document.createElement('option');
      o.value = b.name;
      o.textContent = `${b.name}${b.builtin ? ' (built-in)' : ''}${b.broken ? ' (broken)' : ''}`;
      return o;
    });
    if (!cur || !state.library.some((b) => b.name === cur)) {
      const o = document.createElement('option');
      o.value = '';
      o.textContent = '(untitled)';
      opts.unshift(o);
    }
    ed.select.replaceChildren(...opts);
    ed.select.value = cur && state.library.some((b) => b.name === cur) ? cur : '';
    const e = state.editing;
    const readOnly = e?.builtin || (e?.name && !canWrite(e.name));
    $('.lib-save').disabled = !e?.name || readOnly;
    $('.lib-delete').disabled = !e?.name || e.builtin || !canDelete(e.name);
    $('.library-state').textContent = !e ? '' : (readOnly ? 'read-only: Save as makes a copy' : '') +
      (ed.unsaved() ? ' · unsaved changes' : '');
  };
}

/** The selected object switches to `name` (kept parameter values that still fit). */
async function useForObject(name, params) {
  await switchObject(name, params);
  set({ brdf: { name, params } });
}

/** open(name): a library BRDF's text in the editor, and (with `apply`) the selected object renders it. */
function makeOpen(ed) {
  return async function open(name, { apply = true } = {}) {
    const b = await api.getBrdf(name);
    ed.load(b.source);
    ed.stored = b.source;
    const scratch = name === scratchName(state.session);
    set({ editing: { name: scratch ? null : b.name, builtin: b.builtin, source: b.source }, diagnostics: b.error?.diagnostics || [] });
    if (b.broken) { set({ status: `"${name}" does not parse: fix it and Save` }); return; }
    if (apply) await useForObject(b.name, b.params);
    else set({ brdf: { name: b.name, params: b.params } });
    set({ status: scratch ? 'editing this tab\'s scratch BRDF (Save as to keep it)'
      : b.builtin ? `viewing built-in "${b.name}" (read-only: edits compile into a scratch copy)`
        : !canWrite(b.name) ? `viewing "${b.name}" (read-only: Save as makes your own copy)` : `editing "${b.name}"` });
  };
}

/** Save and Save as: store the text under a name, which the selected object then renders. */
function mountSave(ed) {
  const { $ } = ed;
  async function saveAs(name) {
    const source = ed.text();
    try {
      const b = await api.putBrdf(name, source);
      ed.stored = source;
      set({ editing: { name, builtin: false, source }, diagnostics: b.warnings || [], status: `saved "${name}"` });
      await useForObject(name, b.params);
      await refreshLibrary();
    } catch (e) {
      if (e.body?.diagnostics) set({ diagnostics: e.body.diagnostics });
      set({ status: `save: ${e.message}` });
    }
  }
  $('.lib-save').addEventListener('click', () => {
    const e = state.editing;
    if (e?.name && !e.builtin && canWrite(e.name)) saveAs(e.name);
  });
  $('.lib-saveas').addEventListener('click', () => {
    // A student's BRDFs are saved under their namespace (alice/NAME): they type NAME.
    const ns = namespace();
    const suggestion = state.editing?.name ? `${bareName(state.editing.name)}_copy` : 'my_brdf';
    let bare = prompt(`Save as (letters, digits, _ and -, at most 64${ns ? `; saved as ${ns}NAME` : ''}):`, suggestion);
    if (bare == null) return;
    if (ns && bare.startsWith(ns)) bare = bare.slice(ns.length);
    if (!NAME_RE.test(bare) || bare === 'inline' || bare === 'validate') { set({ status: `"${bare}" is not a valid BRDF name` }); return; }
    const name = ownName(bare);
    const existing = state.library.find((b) => b.name === name);
    if (existing?.builtin) { set({ status: `"${name}" is a built-in (read-only): choose another name` }); return; }
    if (existing && !confirm(`Replace the saved BRDF "${name}"?`)) return;
    saveAs(name);
  });
}

/** Delete: the BRDF goes; objects that render it switch to this tab's scratch copy of its text. */
function mountDelete(ed) {
  ed.$('.lib-delete').addEventListener('click', async () => {
    const e = state.editing;
    if (!e?.name || e.builtin || !canDelete(e.name) || !confirm(`Delete "${e.name}" and its presets? Objects using it keep rendering a scratch copy.`)) return;
    try {
      // The server's scene, not only this page's copy: a script may have changed it. The
      // local scene holds every edit of this page too (one not answered yet included).
      await reloadScene().catch(() => null);
      if (state.scene.objects.some((o) => o.brdf === e.name)) {
        // A scene cannot name a deleted BRDF: move its objects to this tab's scratch copy.
        const scratch = scratchName(state.session);
        await api.putBrdf(scratch, e.source);
        await editScene((scene) => ({ objects: scene.objects.map((o) => (o.brdf === e.name ? { ...o, brdf: scratch } : o)) }));
        if (state.brdf?.name === e.name) set({ brdf: { ...state.brdf, name: scratch } });
      }
      await api.deleteBrdf(e.name);
      set({ editing: { name: null, builtin: false, source: ed.text() }, status: `deleted "${e.name}"` });
      await refreshLibrary();
    } catch (err) {
      set({ status: `delete: ${err.message}` });
    }
  });
}

/** Opening from the list, New and Revert. */
function mountOpenNewRevert(ed) {
  const { $, select } = ed;
  select.addEventListener('change', async () => {
    const name = select.value;
    if (!name) return;
    if (!ed.okToDiscard()) { ed.showLibrary(); return; }
    try { await ed.open(name); } catch (e) { set({ status: `open: ${e.message}` }); ed.showLibrary(); }
  });
  $('.lib-new').addEventListener('click', () => {
    if (!ed.okToDiscard()) return;
    ed.load(TEMPLATE);
    set({ editing: { name: null, builtin: false, source: TEMPLATE }, status: 'new BRDF from the template (Save as to name it)' });
    ed.compile();
  });
  $('.lib-revert').addEventListener('click', async () => {
    const e = state.editing;
    if (!e || !ed.unsaved() || !confirm('Revert to the saved text? Your changes are lost.')) return;
    if (e.name) { try { await ed.open(e.name); } catch (err) { set({ status: `revert: ${err.message}` }); } return; }
    ed.load(e.source);
    ed.compile();
  });
}

export function mountEditor(el, libEl) {
  // What the sub-views share: the view, the text the server last accepted (scratch or a saved
  // name), and the operations on them.
  const ed = { stored: null, $: (c) => libEl.querySelector(c) };
  ed.select = ed.$('.library-list');
  ed.compile = makeCompile(ed);
  ed.showLibrary = makeShowLibrary(ed);
  ed.open = makeOpen(ed);
  const view = createView(el, ed);
  ed.text = () => view.state.doc.toString();
  ed.load = (source) => view.dispatch({ changes: { from: 0, to: view.state.doc.length, insert: source } });
  /** Differs from the version saved under a name (or, untitled, from what it started as). */
  ed.unsaved = () => state.editing && ed.text() !== state.editing.source;
  ed.okToDiscard = () => !ed.unsaved() || confirm('The editor has unsaved changes. Discard them?');

  mountDiagnostics(el, view);
  el.querySelector('.compile').addEventListener('click', ed.compile);
  on('library', ed.showLibrary);
  on('editing', ed.showLibrary);
  // Leaving loses only text the server never got (scratch compiles are stored).
  window.addEventListener('beforeunload', (ev) => {
    if (ed.stored !== null && ed.text() !== ed.stored) { ev.preventDefault(); ev.returnValue = ''; }
  });
  mountOpenNewRevert(ed);
  mountSave(ed);
  mountDelete(ed);

  // The selected object changed, or switched to another BRDF (the Objects tab): show its text, unless
  // the user keeps unsaved text.
  on('brdf', ({ brdf }) => {
    if (!brdf || brdf.name === scratchName(state.session) || brdf.name === state.editing?.name) return;
    if (ed.unsaved() && !confirm(`Object ${state.selected + 1} uses "${brdf.name}". Load its text into the editor and discard your changes?`)) return;
    ed.open(brdf.name, { apply: false }).catch((e) => set({ status: `open: ${e.message}` }));
  });

  ed.showLibrary();
  return {
    /** Replaces the text without compiling (loading a BRDF). */
    load: ed.load,
    /** The BRDF the selected object uses at start: shown, not re-applied. */
    openInitial: (name) => ed.open(name, { apply: false }),
  };
}
