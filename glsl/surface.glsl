/* The shading point: geometry and material inputs every model reads. */

struct Surface {
  vec3 p;             /* world position */
  vec3 n;             /* unit shading normal, flipped towards the viewer on back faces */
  vec3 v;             /* unit direction towards the viewer */
  float NoV;          /* n.v floored at MIN_COS (grazing and silhouette fragments) */
  vec3 base_color;
  vec3 diffuse_color;
  vec3 specular_color;
  vec3 ambient_color;
  float roughness;    /* perceptual roughness r, floored at MIN_PERCEPTUAL_ROUGHNESS */
  float alpha;        /* GGX alpha = r^2 (Burley 2012) */
  float metalness;
  float shininess;
  float f0_dielectric;
  vec3 f0;            /* mix(F0 dielectric, base colour, metalness) */
  float f90;          /* Schlick's grazing reflectance: saturate(50 F0) unless the material sets it */
  float fresnel_p;    /* eq. 1.13's p (1/5 gives eq. 1.11) */
  float eta;          /* dielectric IOR from F0: (1 + sqrt F0) / (1 - sqrt F0) */
  bool has_complex_ior;
  vec3 ior_n;         /* conductor's complex IOR n + ik per channel (exact Fresnel) */
  vec3 ior_k;
};

/* Unit half vector of eq. 1.6; l + v = 0 only when the light is exactly behind the viewer's
 * line of sight, where any unit vector serves: fall back to n. */
vec3 half_vector(vec3 l, vec3 v, vec3 n)
{
  vec3 s = l + v;
  float len2 = dot(s, s);
  return len2 > 1e-12 ? s * inversesqrt(len2) : n;
}
