/* Plain types and vector helpers for the per-ray kernel code.
 * This header and its siblings are written in the subset of C that is valid
 * C++ and valid OpenCL C 1.2, so the CPU backends and the device compile the
 * same text. Only sqrt, fabs, ilogb, ldexp and nextafter are used from the math library. Compile
 * without floating-point contraction on both sides (-ffp-contract=off; the
 * pragma below for OpenCL) so both agree bit for bit on walk decisions. */
#ifndef RTCD_KERNEL_TYPES_H
#define RTCD_KERNEL_TYPES_H

#ifdef __OPENCL_C_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#define RTCD_GLOBAL __global
#define RTCD_INLINE static inline
#define RTCD_ALWAYS_INLINE static inline __attribute__((always_inline))
#define RTCD_SQRT(x) sqrt(x)
#define RTCD_FABS(x) fabs(x)
#define RTCD_ILOGB(x) ilogb(x)
#define RTCD_LDEXP(x, e) ldexp(x, e)
#define RTCD_NEXTAFTER(x, y) nextafter(x, y)
typedef uint rtcd_uint;
typedef int rtcd_int;
typedef uchar rtcd_uchar;
typedef ulong rtcd_ulong;
/* Double precision where the device has it (the ray origins' placement);
 * the host places rays for a device without it. */
#if defined(cl_khr_fp64) && !defined(RTCD_NO_FP64)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define RTCD_HAS_DOUBLE 1
#endif
#else
#include <math.h>
#include <stdint.h>
#define RTCD_GLOBAL
#define RTCD_INLINE static inline
#define RTCD_ALWAYS_INLINE static inline __attribute__((always_inline))
#define RTCD_SQRT(x) sqrtf(x)
#define RTCD_FABS(x) fabsf(x)
#define RTCD_ILOGB(x) ilogbf(x)
#define RTCD_LDEXP(x, e) ldexpf(x, e)
#define RTCD_NEXTAFTER(x, y) nextafterf(x, y)
typedef uint32_t rtcd_uint;
typedef int32_t rtcd_int;
typedef uint8_t rtcd_uchar;
typedef uint64_t rtcd_ulong;
#define RTCD_HAS_DOUBLE 1
#endif

/* Three packed floats: 12 bytes, the layout of the host's position arrays. */
typedef struct {
  float x, y, z;
} rtcd_vec3;

RTCD_INLINE rtcd_vec3 rtcd_v3(float x, float y, float z) {
  rtcd_vec3 r;
  r.x = x;
  r.y = y;
  r.z = z;
  return r;
}
RTCD_INLINE rtcd_vec3 rtcd_sub(rtcd_vec3 a, rtcd_vec3 b) { return rtcd_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
RTCD_INLINE rtcd_vec3 rtcd_neg(rtcd_vec3 a) { return rtcd_v3(-a.x, -a.y, -a.z); }
RTCD_INLINE float rtcd_dot(rtcd_vec3 a, rtcd_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
RTCD_INLINE float rtcd_component(rtcd_vec3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

/* A float's bits in an int and back (an edge's clearance rides in an
 * outcome's int field; unions pun in C, OpenCL C and GCC's C++). */
RTCD_INLINE rtcd_int rtcd_float_bits(float f) {
  union {
    float f;
    rtcd_int i;
  } u;
  u.f = f;
  return u.i;
}
RTCD_INLINE float rtcd_bits_float(rtcd_int i) {
  union {
    float f;
    rtcd_int i;
  } u;
  u.i = i;
  return u.f;
}

/* How a ray's line ended up against the target surface. Shared by the walk,
 * the full tracers and the basic volumes, so statistics read the same. */
typedef enum {
  RTCD_LINE_HIT = 0,        /* leaves the target through this triangle at t >= 0: the origin is inside */
  RTCD_LINE_BEHIND = 1,     /* leaves the target at t < 0: the origin is outside, -t away */
  RTCD_LINE_FRONT = 2,      /* the located crossing enters the target: no penetration there */
  RTCD_LINE_BOUNDARY = 3,   /* the walk left the mesh through a boundary edge */
  RTCD_LINE_MISS = 4,       /* the line passes beside the surface (walk turned back at a silhouette) */
  RTCD_LINE_STEP_LIMIT = 5, /* the walk used its step budget (concave trap) */
  RTCD_LINE_PARALLEL = 6    /* the triangle is edge-on to the ray (or has zero area) */
} rtcd_line_status;
#define RTCD_LINE_STATUS_COUNT 7

#endif
