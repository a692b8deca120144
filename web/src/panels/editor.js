// BRDF editor: CodeMirror 6 with GLSL highlighting (the `shader` mode of
// @codemirror/legacy-modes' clike family: GLSL keywords, types and built-ins; the .brdf
// `::begin` lines are plain text to it). Compiles on Ctrl+Enter and after a pause in typing;
// the server's 422 diagnostics become lint markers in the gutter and messages on their lines.
// A successful compile is stored as this session's scratch BRDF and objects[0] switches to it.
import { EditorView, basicSetup } from 'codemirror';
import { keymap } from '@codemirror/view';
import { Prec, Transaction } from '@codemirror/state';
import { StreamLanguage } from '@codemirror/language';
import { shader } from '@codemirror/legacy-modes/mode/clike';
import { setDiagnostics, lintGutter } from '@codemirror/lint';
import * as api from '../api.js';
import { state, set, on } from '../state.js';

const IDLE_MS = 800;   // a pause in typing this long compiles

// A per-session name so tabs never overwrite each other's work (names: [A-Za-z0-9_-]{1,64}).
export const scratchName = (session) => `scratch-${session}`;

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

export function mountEditor(el) {
  const list = el.querySelector('.diagnostics');
  const status = el.querySelector('.status');
  let idle = 0;
  let busy = false;
  let again = false;

  const view = new EditorView({
    parent: el.querySelector('.editor-host'),
    extensions: [
      basicSetup,
      StreamLanguage.define(shader),
      lintGutter(),
      Prec.highest(keymap.of([{ key: 'Mod-Enter', run: () => { compile(); return true; } }])),
      EditorView.updateListener.of((u) => {
        // Only the user's edits start the idle timer, not loading a BRDF's source.
        if (!u.docChanged || !u.transactions.some((tr) => tr.annotation(Transaction.userEvent))) return;
        clearTimeout(idle);
        idle = setTimeout(compile, IDLE_MS);
      }),
    ],
  });

  async function compile() {
    clearTimeout(idle);
    if (!state.session || !state.scene) return;
    if (busy) { again = true; return; }   // one compile at a time; the newest text runs next
    busy = true;
    const source = view.state.doc.toString();
    const name = scratchName(state.session);
    set({ status: 'compiling…' });
    try {
      const brdf = await api.putBrdf(name, source);
      const params = keptParams(state.scene.objects[0]?.params, brdf.params);
      const objects = state.scene.objects.map((o, i) => (i === 0 ? { ...o, brdf: name, params } : o));
      const scene = await api.patchScene(state.session, { objects });
      set({ scene, brdf: { name, params: brdf.params }, diagnostics: brdf.warnings || [],
            status: brdf.cached ? 'compiled (cached)' : `compiled in ${brdf.compile_ms.toFixed(0)} ms` });
    } catch (e) {
      const diagnostics = e.body?.diagnostics || [];
      set({ diagnostics, status: e.status === 422 ? `${diagnostics.length} compile error(s)` : `compile: ${e.message}` });
    } finally {
      busy = false;
      if (again) { again = false; compile(); }
    }
  }

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
  el.querySelector('.compile').addEventListener('click', compile);

  return {
    /** Replaces the text without compiling (loading a BRDF). */
    load(source) {
      view.dispatch({ changes: { from: 0, to: view.state.doc.length, insert: source } });
    },
  };
}
