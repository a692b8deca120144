// Log panel: device and render numbers (the thesis engine's ImGui log window).
import { on } from '../state.js';
import { errPct, fixed } from '../format.js';

export function mountLog(el) {
  const field = (name) => el.querySelector(`[data-k="${name}"]`);
  on('health', ({ health }) => {
    const d = health?.device;
    field('device').textContent = d ? `${d.name} (${d.type})` : 'n/a';
  });
  on('stats', ({ stats }) => {
    if (!stats) return;
    field('fps').textContent = fixed(stats.fps);
    field('ms').textContent = fixed(stats.ms_per_frame);
    field('vertices').textContent = String(stats.vertices);
    field('spp').textContent = String(stats.spp);
    field('err').textContent = errPct(stats.rel_error);
    field('estimator').textContent = stats.estimator || stats.sampling || '';
    field('estimator').title = (stats.warnings || []).join('\n');
    field('nan').textContent = String(stats.nan_samples);
    field('error').textContent = stats.error ? `${stats.error.error}: ${stats.error.message}` : '';
  });
}
