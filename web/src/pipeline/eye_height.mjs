// The camera's height above the floor that the ground cue of the metric scale accepts
// (scale/ground_scale.hpp: the scale is eyeHeight / the cameras' height above the map's floor):
// from a low seat (about 1.2 m) to a tall standing adult (1.8 m), with margin. One range for the
// browser app, the command line and the pipeline itself.
export const EYE_HEIGHT_MIN = 0.8;
export const EYE_HEIGHT_MAX = 3;

/** null when h (metres) is a usable camera height, else what is wrong with it. */
export function eyeHeightError(h) {
  if (typeof h !== 'number' || !Number.isFinite(h) || h < EYE_HEIGHT_MIN || h > EYE_HEIGHT_MAX) {
    return `the camera height above the floor must be between ${EYE_HEIGHT_MIN} and ${EYE_HEIGHT_MAX} m, not ${h}`;
  }
  return null;
}
