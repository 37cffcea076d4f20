/* The integer hashes Cycles' procedural textures are built on (Cycles' util/hash.h): Bob
 * Jenkins' lookup3 final mix of one to four 32-bit keys, a float hashed by its bits, the result
 * mapped to [0, 1]. Bit for bit what Cycles computes (unsigned arithmetic wraps in GLSL as in C);
 * the numpy twin is addon/reference/hashing.py. Compiled into a program only where its graph
 * uses a procedural texture (codegen.OPTIONAL_LIBRARY). */

uint hash_rot(uint x, int k) { return (x << k) | (x >> (32 - k)); }

/* lookup3's mix(a, b, c): the three words of state stirred before the fourth key */
void hash_mix(inout uint a, inout uint b, inout uint c)
{
  a -= c; a ^= hash_rot(c, 4); c += b;
  b -= a; b ^= hash_rot(a, 6); a += c;
  c -= b; c ^= hash_rot(b, 8); b += a;
  a -= c; a ^= hash_rot(c, 16); c += b;
  b -= a; b ^= hash_rot(a, 19); a += c;
  c -= b; c ^= hash_rot(b, 4); b += a;
}

/* lookup3's final(a, b, c): c is the hash */
uint hash_final(uint a, uint b, uint c)
{
  c ^= b; c -= hash_rot(b, 14);
  a ^= c; a -= hash_rot(c, 11);
  b ^= a; b -= hash_rot(a, 25);
  c ^= b; c -= hash_rot(b, 16);
  a ^= c; a -= hash_rot(c, 4);
  b ^= a; b -= hash_rot(a, 14);
  c ^= b; c -= hash_rot(b, 24);
  return c;
}

/* the state's seed for n keys: 0xdeadbeef + (n << 2) + 13 */
uint hash_uint(uint kx)
{
  uint s = 0xdeadbeefu + (1u << 2) + 13u;
  return hash_final(s + kx, s, s);
}

uint hash_uint2(uint kx, uint ky)
{
  uint s = 0xdeadbeefu + (2u << 2) + 13u;
  return hash_final(s + kx, s + ky, s);
}

uint hash_uint3(uint kx, uint ky, uint kz)
{
  uint s = 0xdeadbeefu + (3u << 2) + 13u;
  return hash_final(s + kx, s + ky, s + kz);
}

uint hash_uint4(uint kx, uint ky, uint kz, uint kw)
{
  uint s = 0xdeadbeefu + (4u << 2) + 13u;
  uint a = s + kx, b = s + ky, c = s + kz;
  hash_mix(a, b, c);
  return hash_final(a + kw, b, c);
}

/* [0, 2^32 - 1] -> [0, 1]: Cycles' uint_to_float_incl, whose 1 / (float)0xFFFFFFFF is 2^-32 in
 * single precision (0xFFFFFFFF rounds to 2^32); the conversion rounds as C's does */
float hash_uint_to_unit(uint n) { return float(n) * (1.0 / 4294967296.0); }

float hash_float_to_float(float k) { return hash_uint_to_unit(hash_uint(floatBitsToUint(k))); }
float hash_vec2_to_float(vec2 k) { return hash_uint_to_unit(hash_uint2(floatBitsToUint(k.x), floatBitsToUint(k.y))); }

float hash_vec3_to_float(vec3 k)
{
  uvec3 u = floatBitsToUint(k);
  return hash_uint_to_unit(hash_uint3(u.x, u.y, u.z));
}

float hash_vec4_to_float(vec4 k)
{
  uvec4 u = floatBitsToUint(k);
  return hash_uint_to_unit(hash_uint4(u.x, u.y, u.z, u.w));
}

/* vectors of hashes: the key with 1, 2 appended (or its components rotated) per component, as
 * Cycles' hash_float*_to_float* */
vec2 hash_vec2_to_vec2(vec2 k) { return vec2(hash_vec2_to_float(k), hash_vec3_to_float(vec3(k, 1.0))); }

vec3 hash_vec3_to_vec3(vec3 k)
{
  return vec3(hash_vec3_to_float(k), hash_vec4_to_float(vec4(k, 1.0)), hash_vec4_to_float(vec4(k, 2.0)));
}

vec4 hash_vec4_to_vec4(vec4 k)
{
  return vec4(hash_vec4_to_float(k), hash_vec4_to_float(k.wxyz), hash_vec4_to_float(k.zwxy),
              hash_vec4_to_float(k.yzwx));
}

/* two hashes of a 3 or 4 component key, the second of its components rotated, as Cycles'
 * hash_float3_to_float2 (zxy) and hash_float4_to_float2 (zxwy) */
vec2 hash_vec3_to_vec2(vec3 k) { return vec2(hash_vec3_to_float(k), hash_vec3_to_float(k.zxy)); }
vec2 hash_vec4_to_vec2(vec4 k) { return vec2(hash_vec4_to_float(k), hash_vec4_to_float(k.zxwy)); }

vec3 hash_float_to_vec3(float k)
{
  return vec3(hash_float_to_float(k), hash_vec2_to_float(vec2(k, 1.0)), hash_vec2_to_float(vec2(k, 2.0)));
}

vec3 hash_vec2_to_vec3(vec2 k)
{
  return vec3(hash_vec2_to_float(k), hash_vec3_to_float(vec3(k, 1.0)), hash_vec3_to_float(vec3(k, 2.0)));
}

vec3 hash_vec4_to_vec3(vec4 k)
{
  return vec3(hash_vec4_to_float(k), hash_vec4_to_float(k.zxwy), hash_vec4_to_float(k.wzyx));
}

/* Cycles 5.0's hashes of integer cells (util/hash.h hash_pcg*d_i, after Jarzynski and Olano,
 * "Hash Functions for GPU Rendering", JCGT 2020, kept in signed integers): int multiplication
 * and addition wrap as C's, >> shifts the sign in as C's does on signed ints; the result's 31
 * bits mapped to [0, 1) by 2^-31 (Cycles' 1 / (float)0x7FFFFFFF, which rounds to 2^31). */
ivec2 hash_pcg2d_i(ivec2 v)
{
  v = v * 1664525 + 1013904223;
  v.x += v.y * 1664525;
  v.y += v.x * 1664525;
  v = v ^ (v >> 16);
  v.x += v.y * 1664525;
  v.y += v.x * 1664525;
  return v & 0x7FFFFFFF;
}

ivec3 hash_pcg3d_i(ivec3 v)
{
  v = v * 1664525 + 1013904223;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v = v ^ (v >> 16);
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  return v & 0x7FFFFFFF;
}

ivec4 hash_pcg4d_i(ivec4 v)
{
  v = v * 1664525 + 1013904223;
  v.x += v.y * v.w;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v.w += v.y * v.z;
  v = v ^ (v >> 16);
  v.x += v.y * v.w;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v.w += v.y * v.z;
  return v & 0x7FFFFFFF;
}

vec2 hash_ivec2_to_vec2(ivec2 k) { return vec2(hash_pcg2d_i(k)) * (1.0 / 2147483648.0); }
vec3 hash_ivec3_to_vec3(ivec3 k) { return vec3(hash_pcg3d_i(k)) * (1.0 / 2147483648.0); }
vec4 hash_ivec4_to_vec4(ivec4 k) { return vec4(hash_pcg4d_i(k)) * (1.0 / 2147483648.0); }
/* a 2D cell's colour: the 3D hash of (x, y, 0); a 4D cell's: the first three of its 4D hash */
vec3 hash_ivec2_to_vec3(ivec2 k) { return hash_ivec3_to_vec3(ivec3(k, 0)); }
vec3 hash_ivec4_to_vec3(ivec4 k) { return hash_ivec4_to_vec4(k).xyz; }
