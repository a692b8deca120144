// The BRDF library and the asset list as state (not a panel): refreshed at start and after a
// save, delete or upload; panels listen to `library` and `assets`.
import * as api from './api.js';
import { state, set } from './state.js';

export const NAME_RE = /^[A-Za-z0-9_-]{1,64}$/;
/** The name after its owner's part: `my_ggx` of `alice/my_ggx`. */
export const bareName = (name) => name.slice(name.lastIndexOf('/') + 1);
/** Scratch BRDFs ([owner/]scratch-<session>) belong to one tab each: not listed. */
export const isScratch = (name) => bareName(name).startsWith('scratch-');
/** Where this person's BRDFs live: `alice/` for a student, '' for the teacher (and in none mode). */
export const namespace = () => state.me?.namespace || '';
/** The full name this person saves `bare` under. */
export const ownName = (bare) => `${namespace()}${bare}`;
/**
 * Whether this person may change the (non-built-in) BRDF `name`: a student only their own, the
 * teacher the course library (bare names), never a student's.
 */
export const canWrite = (name) => (namespace() ? name.startsWith(namespace()) : !name.includes('/'));
/** Whether this person may delete it: the teacher also deletes students' BRDFs. */
export const canDelete = (name) => canWrite(name) || state.me?.role === 'teacher';

export async function refreshLibrary() {
  try {
    set({ library: (await api.listBrdfs()).filter((b) => !isScratch(b.name)) });
  } catch (e) {
    set({ status: `library: ${e.message}` });
  }
}

export async function refreshAssets() {
  try {
    set({ assets: await api.listAssets() });
  } catch (e) {
    set({ status: `assets: ${e.message}` });
  }
}
