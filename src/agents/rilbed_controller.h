/* rilbed's C controller API, in the spirit of SPREAD's memory-mapped I/O (paper 000
 * §5.2, §6.5): a controller reads its sensors with rilbed_peek() and drives its motors
 * with rilbed_poke() on a per-robot register map, between an init and a cleanup call.
 * An embedded-style C controller written against these registers compiles unchanged
 * for the simulator: rilbed calls init once, step once per control period, cleanup once
 * at the end, each with the registers of the robot being controlled.
 *
 * One process runs many robots with the same controller, so C static variables are
 * shared between them: keep per-robot state in the user registers (RILBED_REG_USER_0..),
 * which are the robot's own memory and start at 0. (C controllers are stepped one at a
 * time even on `--threads N`, for the same reason.) */
#ifndef RILBED_CONTROLLER_H
#define RILBED_CONTROLLER_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Register addresses. R: read only, W: written by the controller, RW: both. */
enum rilbed_register {
  RILBED_REG_ID = 0x00,           /* R: the robot's ID */
  RILBED_REG_TIME_MS = 0x01,      /* R: simulated time, milliseconds (wraps at 2^31) */
  RILBED_REG_PERIOD_MS = 0x02,    /* R: control period, milliseconds */
  RILBED_REG_PROX_0 = 0x10,       /* R: proximity sensors 0..7 at 0x10..0x17, 0..1023 (-1: none) */
  RILBED_REG_ODO_LEFT = 0x20,     /* R: left wheel counter, pulses of 0.08 mm (low 32 bits) */
  RILBED_REG_ODO_RIGHT = 0x21,    /* R: right wheel counter */
  RILBED_REG_RANGE_COUNT = 0x28,  /* R: number of range finders (up to 8) */
  RILBED_REG_RANGE_0 = 0x30,      /* R: range finder i at 0x30+i, millimetres; -1: nothing in range */
  RILBED_REG_TRACK_COUNT = 0x38,  /* R: number of track sensors (up to 16) */
  RILBED_REG_TRACK_0 = 0x40,      /* R: track sensor i at 0x40+i, 0..its Max Value */
  RILBED_REG_BEACON_COUNT = 0x50, /* R: number of beacons in view (up to 8) */
  RILBED_REG_BEACON_0 = 0x60,     /* R: beacon i: ID at 0x60+2i, bearing at 0x61+2i in millidegrees CCW from ahead */
  RILBED_REG_POSE_VALID = 0x70,   /* R: 1 if the pose registers hold the robot's pose */
  RILBED_REG_POSE_X_MM = 0x71,    /* R: field x, millimetres */
  RILBED_REG_POSE_Y_MM = 0x72,    /* R: field y, millimetres */
  RILBED_REG_POSE_HEADING_MDEG = 0x73, /* R: heading, millidegrees CCW from +x, [0, 360000) */
  RILBED_REG_MOTOR_LEFT = 0x80,        /* RW: left wheel speed, Khepera units (pulses/10 ms, clamped to +-127) */
  RILBED_REG_MOTOR_RIGHT = 0x81,       /* RW: right wheel speed */
  RILBED_REG_BEHAVIOUR = 0x82,         /* RW: behaviour code shown in the run's records (0 = "c0", ... 7 = "c7") */
  RILBED_REG_USER_0 = 0x100,           /* RW: 256 words of per-robot memory, 0x100..0x1FF */
  RILBED_REG_COUNT = 0x200             /* one past the last address */
};

/* Value at `address` of the current robot's register map; 0 for an address outside it. */
int32_t rilbed_peek(uint32_t address);

/* Writes `value` at `address`. Writes to read-only or unknown addresses are ignored
 * (and counted, so that rilbed can warn about them). */
void rilbed_poke(uint32_t address, int32_t value);

/* A C controller: three functions rilbed calls with the robot's registers current. */
typedef struct rilbed_c_controller {
  const char* name;      /* the name a scenario uses: `controller: c:<name>` */
  void (*init)(void);    /* once, before the first step (sensor registers already filled); may be NULL */
  void (*step)(void);    /* once per control period */
  void (*cleanup)(void); /* once when the run ends; may be NULL */
} rilbed_c_controller;

#ifdef __cplusplus
}
#endif

#endif /* RILBED_CONTROLLER_H */
