// Who this page is (docs/api.md, Identities and ownership): GET /api/auth/me at start. Without a
// known identity the page shows, instead of the app, either the join screen (the URL carries the
// teacher's ?join=CODE: a display name, then POST /api/auth/join gives this browser its own
// token) or a screen asking for a token or a join link. The header says who is signed in.
// Everything a person chose (their display name) is shown as text, never as HTML.
import * as api from '../api.js';

/** What a server without identities (`--auth none`, or one older than them) amounts to. */
const NOBODY = { mode: 'none', user: null, display_name: null, role: 'teacher', namespace: '' };

/**
 * Resolves with the identity (the GET /api/auth/me answer) once this page has one: at once when
 * the held token (or none mode) is accepted, else after the person joins or pastes a token.
 * `reason` replaces the opening line of the token screen (a token revoked while in use).
 */
export async function authenticate(el, { reason = '' } = {}) {
  if (!reason) {
    try {
      return { ...NOBODY, ...(await api.me()) };
    } catch (e) {
      if (e.status === 404) return NOBODY;   // no identities on this server: single-user
      if (e.status !== 401) throw e;
      if (api.getToken()) {
        api.clearToken();   // unknown or revoked: it would only be refused again
        reason = 'The token this browser held is no longer accepted.';
      }
    }
  }
  const code = new URL(location.href).searchParams.get('join');
  return new Promise((resolve) => show(el, { code, reason, done: resolve }));
}

function show(el, { code, reason, done }) {
  const $ = (c) => el.querySelector(c);
  const joinForm = $('.auth-join');
  const tokenForm = $('.auth-token');
  const message = $('.auth-message');
  const say = (text) => { message.textContent = text; message.hidden = !text; };
  const main = document.querySelector('main');
  main.hidden = true;
  el.hidden = false;
  joinForm.hidden = !code;
  tokenForm.hidden = !!code;
  $('.auth-reason').textContent = reason;
  $('.auth-reason').hidden = !reason;
  say('');

  const finish = async () => {
    const me = await api.me();   // the new token's identity, as the server sees it
    el.hidden = true;
    main.hidden = false;
    done({ ...NOBODY, ...me });
  };

  joinForm.onsubmit = async (ev) => {
    ev.preventDefault();
    const name = $('.auth-name').value.trim();
    if (!name) { say('Choose a display name first.'); return; }
    const button = joinForm.querySelector('button');
    button.disabled = true;
    say('joining…');
    try {
      const joined = await api.join(code, name);
      api.setToken(joined.token);
      // The code has done its work: a reload or a shared address must not join again.
      const u = new URL(location.href);
      u.searchParams.delete('join');
      history.replaceState(null, '', u);
      await finish();
    } catch (e) {
      say(e.status === 404 ? 'This join link is unknown or has expired: ask your teacher for a new one.'
        : `Could not join: ${e.message}`);
    } finally {
      button.disabled = false;
    }
  };

  tokenForm.onsubmit = async (ev) => {
    ev.preventDefault();
    const token = $('.auth-token-input').value.trim();
    if (!token) { say('Paste a token first.'); return; }
    api.setToken(token);
    try {
      await finish();
    } catch (e) {
      api.clearToken();
      say(e.status === 401 ? 'That token is not accepted.' : `Could not sign in: ${e.message}`);
    }
  };
  (code ? $('.auth-name') : $('.auth-token-input')).focus();
}

/** The header's "who am I": display name, role and mode; hidden in none mode (single-user). */
export function mountWhoAmI(el, me) {
  if (me.mode === 'none') { el.hidden = true; return; }
  el.querySelector('.whoami-name').textContent = me.display_name || me.user || '';
  el.querySelector('.whoami-name').title = me.user ? `user ${me.user}` : '';
  el.querySelector('.whoami-role').textContent = me.role;
  el.querySelector('.whoami-mode').textContent = `${me.mode} mode`;
  const out = el.querySelector('.whoami-logout');
  out.hidden = me.mode !== 'tokens';   // proxy mode: the single sign-on front signs out
  out.onclick = async () => {
    if (!confirm('Sign out? This browser forgets its token; you need a join link or a token to come back.')) return;
    try { await api.logout(); } catch { /* revoked already: forget it all the same */ }
    api.clearToken();
    const u = new URL(location.href);
    u.searchParams.delete('session');
    location.assign(u);
  };
  el.hidden = false;
}
