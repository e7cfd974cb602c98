// The package's "hawor/export": a pipeline result (hawor/pipeline's runPipeline) as files, in
// node and in a browser. world.npz, hands_cam.npz, camera.tum and result.json come from
// ../pipeline/exports.mjs (its header describes each); the animated glTF (GLB) takes the hand
// meshes of handMeshSequence (a core HandModel posed at every frame).
export { resultToWorldNpz, resultToHandsCamNpz, resultToTum, resultToJson } from '../pipeline/exports.mjs';
export { buildGlb } from './gltf.mjs';
export { handMeshSequence } from './hand_meshes.mjs';
