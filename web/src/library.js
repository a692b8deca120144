// The BRDF library and the asset list as state (not a panel): refreshed at start and after a
// save, delete or upload; panels listen to `library` and `assets`.
import * as api from './api.js';
import { set } from './state.js';

export const NAME_RE = /^[A-Za-z0-9_-]{1,64}$/;
/** Scratch BRDFs (scratch-<session>) belong to one tab each: not listed. */
export const isScratch = (name) => name.startsWith('scratch-');

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
