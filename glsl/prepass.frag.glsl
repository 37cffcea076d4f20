/* Depth and normals of the opaque surfaces, ahead of shading, for the occlusion pass: the
 * interpolated normal (flipped towards the viewer on back faces, as the shading does) in world
 * space. */

void main()
{
  vec3 n = world_normal;
  float len2 = dot(n, n);
  n = len2 > 1e-20 ? n * inversesqrt(len2) : vec3(0.0, 0.0, 1.0);
  frag_color = vec4(facing_outward() ? n : -n, 1.0);
}
