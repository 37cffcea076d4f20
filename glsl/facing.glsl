/* Which side of a surface the viewer sees. A mirrored object (negative determinant: an odd number
 * of negative scales) reverses its triangles' winding, so its outward side rasterises as a back
 * face; normal_matrix[3][3] holds the determinant's sign to undo that. Back faces are shaded with
 * the normal flipped towards the viewer, as Cycles does. */
bool facing_outward()
{
  return gl_FrontFacing == (objects.object[object_index].normal_matrix[3][3] > 0.0);
}
