// Compatibility shim: the UI's network module moved to src/api.js (bundled into dist/main.js).
// Kept because the integration test ServesTheWebUi fetches /api.js as a sample static file.
export * from './src/api.js';
