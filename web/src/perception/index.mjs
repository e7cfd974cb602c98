// The perception module: MediaPipe's palm detector and hand landmarker (converted to ONNX at
// install time, web/tools/convert_mediapipe.mjs) with their pre- and post-processing.
export * from './geometry.mjs';
export * from './palm.mjs';
export * from './landmarks.mjs';
export { HandTracker } from './hand_tracker.mjs';
