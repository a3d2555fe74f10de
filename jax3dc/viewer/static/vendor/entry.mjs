// What the viewer uses from npm, bundled into one classic script (global THREE) so that the page
// also works from a file URL, where browsers refuse to load ES modules from other files.
export * from 'three';
export { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
