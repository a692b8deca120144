// Test window (the thesis's batch test): choose BRDFs (or all), POST /api/jobs/validate, poll
// the job with a progress bar and list each result (ok, errors, compile ms, numeric checks)
// with its log. The job runs on the server's own worker pool, so the view keeps rendering.
import * as api from '../api.js';
import { set, on } from '../state.js';

const POLL_MS = 250;
const num = (x, d = 3) => (typeof x === 'number' ? (Math.abs(x) < 1e-3 && x !== 0 ? x.toExponential(1) : x.toFixed(d)) : '');

const CLAIM_SHORT = { reciprocity: 'recip.', 'energy-conservation': 'energy', 'non-negativity': '≥ 0' };

// The file's claims as chips: held, violated (highlighted, the measurement in its tooltip), or
// measured but not claimed (never a failure).
function claimsCell(claims) {
  const td = document.createElement('td');
  td.className = 'claims';
  for (const c of claims || []) {
    const chip = document.createElement('span');
    const state = !c.claimed ? 'unclaimed' : c.holds ? 'holds' : 'violated';
    chip.className = `claim ${state}`;
    chip.dataset.claim = c.name;
    chip.textContent = (state === 'violated' ? '✗ ' : state === 'holds' ? '✓ ' : '') + (CLAIM_SHORT[c.name] || c.name);
    chip.title = `${c.name}: ${state === 'unclaimed' ? 'not claimed (reported only)' : state}. ${c.measured}`;
    td.append(chip);
  }
  return td;
}

export function mountTests(el) {
  const names = el.querySelector('.test-names');
  const all = el.querySelector('.test-all');
  const run = el.querySelector('.test-run');
  const bar = el.querySelector('.test-progress');
  const status = el.querySelector('.test-status');
  const body = el.querySelector('.test-results tbody');
  const log = el.querySelector('.test-log');
  let results = [];
  let shown = -1;       // index of the result whose log is shown

  on('library', ({ library }) => {
    const checked = new Set([...names.querySelectorAll('input:checked')].map((i) => i.value));
    names.replaceChildren(...(library || []).map((b) => {
      const label = document.createElement('label');
      const box = document.createElement('input');
      box.type = 'checkbox';
      box.value = b.name;
      box.checked = checked.has(b.name);
      box.disabled = all.checked;
      label.append(box, ` ${b.name}${b.builtin ? '' : ' *'}`);
      return label;
    }));
  });
  all.addEventListener('change', () => {
    for (const box of names.querySelectorAll('input')) box.disabled = all.checked;
  });

  function showLog(i) {
    shown = i;
    const r = results[i];
    log.textContent = r ? `${r.name}:\n${(r.log || []).join('\n') || '(empty log)'}` +
      (r.checks?.error ? `\ncheck not run: ${r.checks.error}: ${r.checks.message || ''}` : '') : '';
    for (const [j, tr] of [...body.rows].entries()) tr.classList.toggle('selected', j === i);
  }

  function showJob(job) {
    bar.value = job.progress;
    status.textContent = `${job.state}: ${job.finished}/${job.total}` +
      (job.state === 'done' ? `, ${job.results.filter((r) => !r.ok).length} failed` : '');
    results = job.results || [];
    body.replaceChildren(...results.map((r, i) => {
      const tr = document.createElement('tr');
      tr.className = r.ok ? 'ok' : 'fail';
      const c = r.checks || {};
      const cells = [r.name, r.ok ? 'yes' : 'NO', r.errors, num(r.compile_ms, 1) + (r.cached ? ' (cached)' : ''),
        c.error ? c.error : c.nan, c.error ? '' : c.inf, c.error ? '' : c.negative,
        c.max_albedo_std_error ? `${num(c.max_albedo)} ± ${num(c.max_albedo_std_error)}` : num(c.max_albedo),
        num(c.max_reciprocity_error)];
      for (const v of cells) { const td = document.createElement('td'); td.textContent = String(v ?? ''); tr.append(td); }
      tr.append(claimsCell(c.claims));
      const td = document.createElement('td');
      const b = document.createElement('button');
      b.type = 'button';
      b.textContent = 'log';
      b.addEventListener('click', () => showLog(i));
      td.append(b);
      tr.append(td);
      return tr;
    }));
    if (shown < 0 && results.length) showLog(0); else showLog(shown);
  }

  run.addEventListener('click', async () => {
    const chosen = all.checked ? 'all' : [...names.querySelectorAll('input:checked')].map((i) => i.value);
    if (chosen !== 'all' && !chosen.length) { status.textContent = 'choose at least one BRDF (or all)'; return; }
    run.disabled = true;
    shown = -1;
    results = [];
    body.replaceChildren();
    log.textContent = '';
    bar.value = 0;
    try {
      const { id, total } = await api.startValidateJob(chosen);
      status.textContent = `queued: 0/${total}`;
      el.dataset.job = id;
      for (;;) {
        const job = await api.getJob(id);
        showJob(job);
        if (job.state === 'done') break;
        await new Promise((r) => setTimeout(r, POLL_MS));
      }
    } catch (e) {
      status.textContent = `test: ${e.message}`;
      set({ status: `test: ${e.message}` });
    } finally {
      run.disabled = false;
    }
  });
}
