// Skinned positions of a glTF file as three.js computes them (the peer of tests/cli/gltf_peer_test.py).
// Usage: [MORPHS='{"NAME": W}'] node three_skin.mjs MODEL.gltf|MODEL.glb [ANIMATION_INDEX TIME[,TIME...]]
// Prints {"corners": [[x, y, z], ...], "animations": [names]}: the world position of every triangle corner of every
// mesh, in scene order (three's traversal, the glTF node order), posed by AnimationMixer at TIME seconds when an
// animation index is given, else at the node tree's rest. With several times (a comma-separated list) it prints
// {"frames": [corners at each time], "animations": [...]} instead, the animation played once and held at its end
// (LoopOnce, clampWhenFinished), so that a time at the clip's end shows its last key rather than its first. Textures and materials are dropped before loading (there
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

// three.js skins with four influences (JOINTS_0 / WEIGHTS_0); glTF allows more sets (JOINTS_1 / WEIGHTS_1, ...),
// which GLTFLoader keeps as the attributes joints_1 / weights_1. For such meshes the weights are normalised over all
// sets (as three's normalizeSkinWeights does over one) and each vertex is skinned by three's own bone matrices,
// bind matrix and morphed position (Mesh.getVertexPosition), summed over every set — applyBoneTransform's loop,
// extended from 4 influences to all of them.
function extraSets(geometry) {
  const sets = [];
  for (let n = 1; geometry.attributes['joints_' + n] && geometry.attributes['weights_' + n]; ++n)
    sets.push([geometry.attributes['joints_' + n], geometry.attributes['weights_' + n]]);
  return sets;
}
const normalizeFour = THREE.SkinnedMesh.prototype.normalizeSkinWeights;
THREE.SkinnedMesh.prototype.normalizeSkinWeights = function () {
  const sets = extraSets(this.geometry);
  if (sets.length === 0) return normalizeFour.call(this);
  const all = [[this.geometry.attributes.skinIndex, this.geometry.attributes.skinWeight], ...sets];
  const w = new THREE.Vector4();
  for (let i = 0; i < all[1][1].count; ++i) {
    let total = 0;
    for (const [, weights] of all) total += w.fromBufferAttribute(weights, i).manhattanLength();
    if (!(total > 0)) continue;
    for (const [, weights] of all) {
      w.fromBufferAttribute(weights, i).multiplyScalar(1 / total);
      weights.setXYZW(i, w.x, w.y, w.z, w.w);
    }
  }
};
const skinAllSets = function (index, target) {
  const sets = [[this.geometry.attributes.skinIndex, this.geometry.attributes.skinWeight], ...extraSets(this.geometry)];
  const base = target.clone().applyMatrix4(this.bindMatrix);
  const j = new THREE.Vector4(), w = new THREE.Vector4(), m = new THREE.Matrix4(), p = new THREE.Vector3();
  target.set(0, 0, 0);
  for (const [joints, weights] of sets) {
    j.fromBufferAttribute(joints, index);
    w.fromBufferAttribute(weights, index);
    for (let k = 0; k < 4; ++k) {
      const weight = w.getComponent(k);
      if (weight === 0) continue;
      const bone = j.getComponent(k);
      m.multiplyMatrices(this.skeleton.bones[bone].matrixWorld, this.skeleton.boneInverses[bone]);
      target.addScaledVector(p.copy(base).applyMatrix4(m), weight);
    }
  }
  return target.applyMatrix4(this.bindMatrixInverse);
};

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
const times = timeArg === undefined ? [] : timeArg.split(',').map(Number);
let action = null;
if (animationArg !== undefined) {
  action = new THREE.AnimationMixer(scene).clipAction(gltf.animations[Number(animationArg)]);
  if (times.length > 1) {
    action.setLoop(THREE.LoopOnce);
    action.clampWhenFinished = true;
  }
  action.play();
}
// MORPHS='{"NAME": weight, ...}' sets those morph targets' influences (by mesh.extras.targetNames) after the pose.
const setMorphs = () => {
  if (!process.env.MORPHS) return;
  const morphs = JSON.parse(process.env.MORPHS);
  scene.traverse((object) => {
    if (!object.morphTargetDictionary) return;
    for (const [name, weight] of Object.entries(morphs))
      if (name in object.morphTargetDictionary) object.morphTargetInfluences[object.morphTargetDictionary[name]] = weight;
  });
};
scene.traverse((object) => {
  if (object.isSkinnedMesh && extraSets(object.geometry).length > 0) object.applyBoneTransform = skinAllSets;
});
const cornersNow = () => {
  setMorphs();
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
  return corners;
};
const animations = gltf.animations.map((a) => a.name);
if (times.length > 1) {
  const frames = [];
  for (const time of times) {
    action.getMixer().setTime(time);
    frames.push(cornersNow());
  }
  process.stdout.write(JSON.stringify({ frames, animations }));
} else {
  if (action) action.getMixer().update(times[0]);
  process.stdout.write(JSON.stringify({ corners: cornersNow(), animations }));
}
