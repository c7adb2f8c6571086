// Skinned positions of a glTF file as three.js computes them (the peer of tests/cli/gltf_peer_test.py).
// Usage: node three_skin.mjs MODEL.gltf|MODEL.glb [ANIMATION_INDEX TIME]
// Prints {"corners": [[x, y, z], ...], "animations": [names]}: the world position of every triangle corner of every
// mesh, in scene order (three's traversal, the glTF node order), posed by AnimationMixer at TIME seconds when an
// animation index is given, else at the node tree's rest. Textures and materials are dropped before loading (there
// is no DOM to decode images in), and buffers are handed over as data: URIs (node's fetch reads no file: URLs).
import fs from 'node:fs';
import path from 'node:path';
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';

// FileLoader reports progress with the DOM's ProgressEvent, which node lacks.
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) {
    super(type);
    Object.assign(this, init);
  }
};

const [file, animationArg, timeArg] = process.argv.slice(2);
const bytes = fs.readFileSync(file);
let json;
let bin = null;
if (bytes.subarray(0, 4).toString('latin1') === 'glTF') {
  const jsonLength = bytes.readUInt32LE(12);
  json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
  const binStart = 20 + jsonLength;
  if (binStart + 8 <= bytes.length) {
    const binLength = bytes.readUInt32LE(binStart);
    bin = bytes.subarray(binStart + 8, binStart + 8 + binLength);
  }
} else {
  json = JSON.parse(bytes.toString('utf8'));
}
const folder = path.dirname(file);
for (const [i, buffer] of (json.buffers || []).entries()) {
  if (buffer.uri === undefined && i === 0 && bin) {
    buffer.uri = 'data:application/octet-stream;base64,' + bin.toString('base64');
  } else if (buffer.uri !== undefined && !buffer.uri.startsWith('data:')) {
    const data = fs.readFileSync(path.join(folder, decodeURIComponent(buffer.uri)));
    buffer.uri = 'data:application/octet-stream;base64,' + data.toString('base64');
  }
}
delete json.images;
delete json.textures;
delete json.samplers;
delete json.materials;
for (const mesh of json.meshes || []) for (const primitive of mesh.primitives) delete primitive.material;

const loader = new GLTFLoader();
const gltf = await new Promise((resolve, reject) => loader.parse(JSON.stringify(json), '', resolve, reject));
const scene = gltf.scene;
// glTF requires unit rotation keys, but files round them (simple_skin.gltf: |q| = 1 ± 2e-4) and three.js composes
// matrices from the stored keys, which scales the bone by |q|²; libdeform normalises each key, and so does this.
for (const clip of gltf.animations)
  for (const track of clip.tracks) {
    if (!track.name.endsWith('.quaternion')) continue;
    const values = track.values;
    const stride = values.length / track.times.length;  // 4, or 12 for a cubic spline (tangent, value, tangent)
    const offset = stride === 12 ? 4 : 0;
    for (let k = 0; k < track.times.length; ++k) {
      const i = k * stride + offset;
      const length = Math.hypot(values[i], values[i + 1], values[i + 2], values[i + 3]);
      if (length > 0) for (let c = 0; c < 4; ++c) values[i + c] /= length;
    }
  }
if (animationArg !== undefined) {
  const mixer = new THREE.AnimationMixer(scene);
  mixer.clipAction(gltf.animations[Number(animationArg)]).play();
  mixer.update(Number(timeArg));
}
scene.updateMatrixWorld(true);
const corners = [];
const v = new THREE.Vector3();
scene.traverse((object) => {
  if (!object.isMesh) return;
  const geometry = object.geometry;
  const listed = geometry.index ? geometry.index.count : geometry.attributes.position.count;
  const count = listed - (listed % 3);  // a trailing incomplete triangle draws nothing
  for (let i = 0; i < count; ++i) {
    const vertex = geometry.index ? geometry.index.getX(i) : i;
    object.getVertexPosition(vertex, v);
    v.applyMatrix4(object.matrixWorld);
    corners.push([v.x, v.y, v.z]);
  }
});
process.stdout.write(JSON.stringify({ corners, animations: gltf.animations.map((a) => a.name) }));
