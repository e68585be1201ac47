/*
 * Little-endian loads and stores on byte buffers.  File formats are read
 * from buffers of arbitrary alignment, so every access goes through bytes
 * (or memcpy) and never through a cast pointer; compilers turn these into
 * single moves on little-endian hosts.
 */
#ifndef NERF_IO_BYTEORDER_H
#define NERF_IO_BYTEORDER_H

#include <stdint.h>
#include <string.h>

static inline uint16_t nerf__load_le16(const unsigned char *p)
{
    return (uint16_t)(p[0] | (unsigned)p[1] << 8);
}

static inline uint32_t nerf__load_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
           (uint32_t)p[3] << 24;
}

static inline uint64_t nerf__load_le64(const unsigned char *p)
{
    return (uint64_t)nerf__load_le32(p) |
           (uint64_t)nerf__load_le32(p + 4) << 32;
}

static inline float nerf__load_lef32(const unsigned char *p)
{
    uint32_t bits = nerf__load_le32(p);
    float f;
    memcpy(&f, &bits, sizeof f);
    return f;
}

static inline double nerf__load_lef64(const unsigned char *p)
{
    uint64_t bits = nerf__load_le64(p);
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

static inline void nerf__store_le16(unsigned char *p, uint16_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
}

static inline void nerf__store_le32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}

static inline void nerf__store_le64(unsigned char *p, uint64_t v)
{
    nerf__store_le32(p, (uint32_t)v);
    nerf__store_le32(p + 4, (uint32_t)(v >> 32));
}

static inline void nerf__store_lef32(unsigned char *p, float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    nerf__store_le32(p, bits);
}

static inline void nerf__store_lef64(unsigned char *p, double d)
{
    uint64_t bits;
    memcpy(&bits, &d, sizeof bits);
    nerf__store_le64(p, bits);
}

#endif
