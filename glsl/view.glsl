/* The unit direction from p towards the viewer: the camera's position (perspective), or its
 * axis reversed (orthographic: parallel view rays). Reads the frame block. */
vec3 view_direction(vec3 p)
{
  if (frame.camera_position.w > 0.5) {
    return normalize(frame.camera_position.xyz - p);
  }
  return -frame.camera_forward.xyz;
}
