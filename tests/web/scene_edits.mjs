// Browser checks of the scene command layer (web/src/scene-commands.js), run by run.mjs after
// checks.mjs (they use its first tab, env.page and env.sid). Rapid slider moves while the
// answer to the first PATCH is held back: one PATCH at a time, the moves made meanwhile go out
// as one, the server ends on the last value, and the late answer never puts an old value on
// screen.
import assert from 'node:assert/strict';
import { http, until, sleep } from './checks.mjs';

// How long the answer to the first PATCH is held back: far longer than the moves take, so
// every later move is made while it is in flight.
const HOLD_MS = 1500;

/** Holds back the answer to the first PATCH of the session's scene; counts PATCHes in flight. */
async function holdFirstPatch(page, sid) {
  const seen = { patches: 0, inFlight: 0, maxInFlight: 0 };
  const handler = async (route) => {
    if (route.request().method() !== 'PATCH') { await route.continue(); return; }
    const first = seen.patches++ === 0;
    seen.maxInFlight = Math.max(seen.maxInFlight, ++seen.inFlight);
    try {
      const response = await route.fetch();   // the server applies it now ...
      if (first) await sleep(HOLD_MS);          // ... and the page hears of it late
      await route.fulfill({ response });
    } finally {
      seen.inFlight--;
    }
  };
  const url = (u) => u.pathname === `/api/sessions/${sid}/scene`;
  await page.route(url, handler);
  seen.stop = () => page.unroute(url, handler);
  return seen;
}

export const sceneEditChecks = [
  ['rapid slider moves: one PATCH at a time, the last value wins, a late answer puts no old value back', async (env) => {
    const { page, sid } = env;
    await page.bringToFront();
    const slider = await page.evaluate(() => {
      const input = document.querySelector('#params input[type="range"]');
      return input && { name: input.name, min: Number(input.min), max: Number(input.max) };
    });
    assert.ok(slider, 'the Parameters panel has a slider');
    const { name, min, max } = slider;
    // Values on the slider's step (a thousandth of its range), each far from the others.
    const values = [0.9, 0.15, 0.7, 0.3, 0.55].map((f) => min + f * (max - min));
    const final = values.at(-1);
    const seen = await holdFirstPatch(page, sid);
    try {
      // Every text the slider's readout shows, with when it showed it.
      const tLast = await page.evaluate(async ({ name, values }) => {
        const input = document.querySelector(`#params input[name="${name}"]`);
        const readout = input.parentElement.querySelector('output');
        window.__shown = [];
        new MutationObserver(() => window.__shown.push({ t: performance.now(), text: readout.textContent }))
          .observe(readout, { childList: true, characterData: true, subtree: true });
        for (const v of values) {
          input.value = String(v);
          input.dispatchEvent(new Event('input', { bubbles: true }));
          await new Promise((r) => setTimeout(r, 30));   // a drag: one move per frame or so
        }
        return performance.now();
      }, { name, values });
      const tol = (max - min) * 1e-3;
      await until('the server scene to hold the last value', async () =>
        Math.abs((await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].params[name] - final) < tol, 20000);
      await until('no PATCH in flight', async () => seen.patches >= 2 && seen.inFlight === 0, 20000);
      await sleep(300);   // any answer still on its way to the page is shown by now
      assert.equal(seen.maxInFlight, 1, 'one PATCH in flight at a time');
      assert.equal(seen.patches, 2, 'the moves made while the first PATCH was in flight went out as one');
      const text = Number(final).toPrecision(3);
      const after = await page.evaluate((t) => window.__shown.filter((s) => s.t >= t).map((s) => s.text), tLast);
      assert.ok(after.length > 0, 'the answers were shown');
      assert.deepEqual([...new Set(after)], [text], `after the last move only ${text} is shown (shown: ${after.join(', ')})`);
      const shown = await page.evaluate((name) => {
        const input = document.querySelector(`#params input[name="${name}"]`);
        return { value: Number(input.value), readout: input.parentElement.querySelector('output').textContent };
      }, name);
      assert.ok(Math.abs(shown.value - final) < tol, `the slider holds the last value (${shown.value})`);
      assert.equal(shown.readout, text);
    } finally {
      await seen.stop();
    }
  }],
];
