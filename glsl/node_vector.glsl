/* Vector nodes: Mapping, Vector Rotate and Normal, as Cycles evaluates them
 * (intern/cycles/kernel/svm/mapping_util.h svm_mapping, vector_rotate.h svm_node_vector_rotate,
 * normal.h svm_node_normal; util/transform.h euler_to_transform, rotate_around_axis). */

/* Cycles' euler_to_transform: the rows of the rotation X, then Y, then Z (Euler XYZ) */
void euler_rows(vec3 e, out vec3 rx, out vec3 ry, out vec3 rz)
{
  float cx = cos(e.x), cy = cos(e.y), cz = cos(e.z);
  float sx = sin(e.x), sy = sin(e.y), sz = sin(e.z);
  rx = vec3(cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz);
  ry = vec3(cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz);
  rz = vec3(-sy, cy * sx, cy * cx);
}

/* transform_direction: the rotation applied */
vec3 euler_rotate(vec3 e, vec3 v)
{
  vec3 rx, ry, rz;
  euler_rows(e, rx, ry, rz);
  return vec3(dot(rx, v), dot(ry, v), dot(rz, v));
}

/* transform_direction_transposed: its inverse */
vec3 euler_rotate_inverse(vec3 e, vec3 v)
{
  vec3 rx, ry, rz;
  euler_rows(e, rx, ry, rz);
  return rx * v.x + ry * v.y + rz * v.z;
}

/* safe_divide_float3_float3: 0 where the divisor is */
vec3 vector_safe_divide(vec3 a, vec3 b)
{
  return vec3(b.x != 0.0 ? a.x / b.x : 0.0, b.y != 0.0 ? a.y / b.y : 0.0, b.z != 0.0 ? a.z / b.z : 0.0);
}

/* The Mapping node, one function per type */
vec3 node_mapping_point(vec3 v, vec3 location, vec3 rotation, vec3 scale)
{
  return euler_rotate(rotation, v * scale) + location;
}

vec3 node_mapping_texture(vec3 v, vec3 location, vec3 rotation, vec3 scale)
{
  return vector_safe_divide(euler_rotate_inverse(rotation, v - location), scale);
}

vec3 node_mapping_vector(vec3 v, vec3 rotation, vec3 scale) { return euler_rotate(rotation, v * scale); }

/* a normal: through the inverse scale, unit length (a zero vector stays zero: safe_normalize) */
vec3 node_mapping_normal(vec3 v, vec3 rotation, vec3 scale)
{
  vec3 n = euler_rotate(rotation, vector_safe_divide(v, scale));
  float len = length(n);
  return len != 0.0 ? n / len : n;
}

/* Cycles' rotate_around_axis: p about the unit axis by angle (Rodrigues' matrix) */
vec3 vector_rotate_around_axis(vec3 p, vec3 axis, float angle)
{
  float c = cos(angle), s = sin(angle), t = 1.0 - c;
  return vec3((c + t * axis.x * axis.x) * p.x + (t * axis.x * axis.y - axis.z * s) * p.y +
                  (t * axis.x * axis.z + axis.y * s) * p.z,
              (t * axis.x * axis.y + axis.z * s) * p.x + (c + t * axis.y * axis.y) * p.y +
                  (t * axis.y * axis.z - axis.x * s) * p.z,
              (t * axis.x * axis.z - axis.y * s) * p.x + (t * axis.y * axis.z + axis.x * s) * p.y +
                  (c + t * axis.z * axis.z) * p.z);
}

/* Vector Rotate about an axis through center (Invert: the caller negates the angle); a zero
 * axis leaves the vector as it is */
vec3 node_vector_rotate_axis_angle(vec3 v, vec3 center, vec3 axis, float angle)
{
  float len = length(axis);
  return len != 0.0 ? vector_rotate_around_axis(v - center, axis / len, angle) + center : v;
}

vec3 node_vector_rotate_x(vec3 v, vec3 center, float angle)
{
  return vector_rotate_around_axis(v - center, vec3(1.0, 0.0, 0.0), angle) + center;
}

vec3 node_vector_rotate_y(vec3 v, vec3 center, float angle)
{
  return vector_rotate_around_axis(v - center, vec3(0.0, 1.0, 0.0), angle) + center;
}

vec3 node_vector_rotate_z(vec3 v, vec3 center, float angle)
{
  return vector_rotate_around_axis(v - center, vec3(0.0, 0.0, 1.0), angle) + center;
}

vec3 node_vector_rotate_euler(vec3 v, vec3 center, vec3 rotation)
{
  return euler_rotate(rotation, v - center) + center;
}

vec3 node_vector_rotate_euler_inverse(vec3 v, vec3 center, vec3 rotation)
{
  return euler_rotate_inverse(rotation, v - center) + center;
}

/* The Normal node: its stored direction, unit length, and that direction's cosine to the input
 * normal */
vec3 node_normal_direction(vec3 direction) { return normalize(direction); }
float node_normal_dot(vec3 direction, vec3 n) { return dot(normalize(direction), normalize(n)); }
