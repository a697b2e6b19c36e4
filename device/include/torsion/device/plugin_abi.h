/* The device plug-in ABI, version 1: a haptic device as a shared library that Torsion loads at
 * run time (dlopen), e.g. `torsion run scene.json --device hand=plugin:/path/libdev.so:CONFIG`.
 * Plain C on purpose: a plug-in may be built by another compiler, against another C++ runtime,
 * over a vendor SDK (docs/haptic-devices.md, "Writing a device plug-in over a vendor SDK").
 *
 * The library exports one function, TORSION_DEVICE_ENTRY_SYMBOL:
 *
 *     const torsion_device_v1* torsion_device_plugin(void);
 *
 * returning a static table whose first member is the ABI version. The loader reads that first,
 * refuses any version but TORSION_DEVICE_ABI_VERSION with an error naming both, and only then
 * reads the rest. A later version may append members; it will not reorder these.
 *
 * Calls. The loader calls open() once, then info() once, then, from one thread of its own (never
 * the haptic loop's), read() and write() about once per loop tick, and close() once at the end.
 * A plug-in need not be thread-safe: no two calls overlap. By default that thread is in a process
 * of its own, torsion_device_host, so a plug-in that crashes ends only that process (the device
 * is then dead and its force fades); the plug-in sees no difference. read() should return within a
 * small part of the loop's period (1 ms at 1 kHz): the loader waits for it only until a deadline,
 * and a device that misses it counts as not answering that tick (its force fades to zero, as for a
 * built-in device that died). Every returned value is checked: a non-finite number, a quaternion
 * whose norm is not 1 within 1e-3, or a non-zero return code makes that tick's reading invalid.
 *
 * Units: SI (m, rad, N, N m, s). Frames: the device's own base frame; Torsion's scene maps it
 * into the world. Wrench sign: the force and torque the device should apply to the user's hand.
 */
#ifndef TORSION_DEVICE_PLUGIN_ABI_H
#define TORSION_DEVICE_PLUGIN_ABI_H

/* A C header, read by C and C++ plug-ins alike: C's headers and typedefs, not C++'s. */
/* NOLINTBEGIN(modernize-deprecated-headers,modernize-use-using,modernize-redundant-void-arg) */
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TORSION_DEVICE_ABI_VERSION 1u
#define TORSION_DEVICE_ENTRY_SYMBOL "torsion_device_plugin"

/* What the device can do; filled by info(). */
typedef struct torsion_device_info {
  double max_force;  /* N, largest force norm the motors may render (0: no motors) */
  double max_torque; /* N m, largest torque norm */
  double rate_hz;    /* the rate the device's own servo loop expects, Hz (e.g. 1000) */
  char name[64];     /* NUL-terminated, for logs: "simulated 0.3 kg, 40 Hz motors" */
} torsion_device_info;

/* One reading; filled by read(). */
typedef struct torsion_device_state {
  double position[3];    /* m, end effector in the device's base frame */
  double orientation[4]; /* unit quaternion w, x, y, z */
  uint32_t buttons;      /* bit k: button k+1 held (bit 0 grabs, bit 1 releases) */
  int32_t alive;         /* non-zero: the device is in contact with its hardware */
} torsion_device_state;

typedef struct torsion_device_v1 {
  uint32_t abi_version; /* TORSION_DEVICE_ABI_VERSION; must be the first member */
  uint32_t reserved;    /* 0 */
  /* Opens the device described by `config` (the text after the library path, maybe empty).
   * Returns a handle, or NULL with a NUL-terminated reason in error[0..error_size). */
  void* (*open)(const char* config, char* error, size_t error_size);
  /* 0 on success. */
  int (*info)(void* handle, torsion_device_info* out);
  /* Reads pose and buttons at `time` (s, the haptic loop's clock). 0 on success. */
  int (*read)(void* handle, double time, torsion_device_state* out);
  /* Renders `wrench` = fx fy fz (N) tx ty tz (N m), already within the limits of info().
   * 0 on success. */
  int (*write)(void* handle, const double wrench[6]);
  /* Zero the motors and release the hardware. The handle is not used again. */
  void (*close)(void* handle);
} torsion_device_v1;

typedef const torsion_device_v1* (*torsion_device_entry_fn)(void);

#ifdef __cplusplus
}
#endif

/* NOLINTEND(modernize-deprecated-headers,modernize-use-using,modernize-redundant-void-arg) */

#endif /* TORSION_DEVICE_PLUGIN_ABI_H */
