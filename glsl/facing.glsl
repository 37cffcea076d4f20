/* The mesh programs' fragment helpers: which side of a surface the viewer sees, and its normal.
 *
 * Which side of a surface the viewer sees. A mirrored object (negative determinant: an odd number
 * of negative scales) reverses its triangles' winding, so its outward side rasterises as a back
 * face; normal_matrix[3][3] holds the determinant's sign to undo that. Back faces are shaded with
 * the normal flipped towards the viewer, as Cycles does. */
bool facing_outward()
{
  return gl_FrontFacing == (objects.object[object_index].normal_matrix[3][3] > 0.0);
}

/* Interpolated corner normals can be zero (a zero-length custom normal, or opposite normals
 * averaged across a triangle); fall back to the flat face normal from screen derivatives. */
vec3 shading_normal(vec3 p)
{
  float len2 = dot(world_normal, world_normal);
  if (len2 > 1e-20) {
    return world_normal * inversesqrt(len2);
  }
  vec3 face = cross(dFdx(p), dFdy(p));
  float flen2 = dot(face, face);
  return flen2 > 0.0 ? face * inversesqrt(flen2) : vec3(0.0, 0.0, 1.0);
}

/* The flat face's normal at p from screen derivatives (the receiver's plane for shadow lookups),
 * n where the face is degenerate: the forward program and the G-buffer take it here alike. */
vec3 face_normal(vec3 p, vec3 n)
{
  vec3 face = cross(dFdx(p), dFdy(p));
  return dot(face, face) > 1e-30 ? normalize(face) : n;
}
