/* rilbed's sensor-model API: a model of a sensor, written in C or C++ and built as a
 * plug-in library (rilbed/plugin.h), that a scenario mounts on a robot:
 *
 *   sensors:
 *     models:
 *       - {library: build/track_sensor.so, name: track_element, parameters: element.txt,
 *          mount_x_m: 0.02, mount_y_m: 0.012, mount_yaw_deg: 0}
 *
 * A model has paper 000's three functions (§5.3):
 *   create   ("register") once per mount and parameter set: it gets its parameters, read
 *            by rilbed from the mount's own text file and checked against the keys the
 *            model declares (rilbed_sensor_param), the static world and the length of a
 *            quantum (the control period); it returns the model's instance.
 *   sense    ("model") once per robot carrying it at each control instant, with the
 *            robot's pose and the poses of every mobile object: it writes the robot's
 *            readings (value_count numbers), and may mark what it sees for the displays.
 *   destroy  ("clean-up") once, when the run is over.
 *
 * Controllers read the values by the mount's name: C controllers with rilbed_peek
 * (RILBED_REG_MODEL_* in rilbed_controller.h), C++ controllers with Input::model(name).
 * A model whose readings are a floor-track sensor's (`provides = "track"`) has them
 * appended to the robot's track readings instead, read as RILBED_REG_TRACK_* and
 * Input::track(), so that controllers written for rilbed's own track sensor run on it.
 *
 * One instance serves every robot that carries the same mount with the same parameters:
 * keep no per-robot state in it, or key it by robot ID and say concurrent = 0. Noise
 * comes from rilbed (rilbed_sense_call::normal), from the robot's own stream: a reading
 * then does not depend on which robots sensed before it or on the thread. */
#ifndef RILBED_SENSOR_MODEL_H
#define RILBED_SENSOR_MODEL_H

#include <stdint.h>

#include "rilbed/plugin.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One key of a model's parameter file. rilbed reads the file (paper 000's format,
 *   Sensor = {
 *       Height      = 8
 *       Cone Angle  = 30
 *   }
 * or YAML), matches its keys to these ignoring case and treating spaces and underscores
 * alike ("Cone Angle" = "cone_angle"), and refuses an unknown key, a missing one or a bad
 * value with the file, the line and the key. Every value is a number. */
typedef struct rilbed_sensor_param {
  const char* key;      /* as the model's documentation writes it: "Cone Angle" */
  const char* unit;     /* "mm", "deg", "%", ...; "" for a count */
  const char* summary;  /* one line of what it means */
  double default_value; /* used when the file leaves the key out, if has_default */
  int32_t has_default;  /* 0: the file must give it */
  int32_t integer;      /* 1: whole numbers only */
  double min;           /* smallest allowed, inclusive; -HUGE_VAL for none */
  double max;           /* largest allowed, inclusive; HUGE_VAL for none */
} rilbed_sensor_param;

/* A straight piece of the static world, field frame, metres. */
typedef struct rilbed_segment {
  double ax_m, ay_m, bx_m, by_m;
} rilbed_segment;

/* A piece of floor track: a segment and its half width, metres. */
typedef struct rilbed_track_segment {
  double ax_m, ay_m, bx_m, by_m;
  double half_width_m;
} rilbed_track_segment;

/* The static world, as the model's create() gets it: the field (origin at its lower-left
 * corner, x right, y up), wall and obstacle edges, floor tracks. */
typedef struct rilbed_static_world {
  double width_m, height_m;
  const rilbed_segment* segments; /* boundary walls (when on) and obstacle edges */
  uint32_t segment_count;
  const rilbed_track_segment* tracks;
  uint32_t track_count;
} rilbed_static_world;

/* What create() gets. Pointers valid during the call only: copy what the model keeps. */
typedef struct rilbed_sensor_setup {
  uint32_t param_count;        /* the model's parameters, every one, in its declared order */
  const double* param_values;  /* with the defaults filled in */
  double mount_x_m, mount_y_m; /* where it sits on the robot: metres forward, left of the centre */
  double mount_yaw_deg;        /* where it looks: degrees counter-clockwise from the robot's forward */
  int64_t quantum_us;          /* the control period: how often sense() is called per robot */
  const rilbed_static_world* world;
  const char* parameter_file; /* the file the parameters came from, for messages */
} rilbed_sensor_setup;

/* A robot or a moving obstacle, field frame. */
typedef struct rilbed_mobile {
  int32_t id; /* a robot's ID; moving obstacles are numbered -1, -2, ... */
  double x_m, y_m, heading_rad;
} rilbed_mobile;

/* Shapes a model may draw, in the robot's frame (metres, x forward, y left). */
enum rilbed_mark_shape {
  RILBED_MARK_CIRCLE = 1, /* centre (x_m, y_m), radius_m */
  RILBED_MARK_LINE = 2    /* from (x_m, y_m) to (x2_m, y2_m) */
};
typedef struct rilbed_mark {
  int32_t shape;
  double x_m, y_m;
  double radius_m;
  double x2_m, y2_m;
  uint32_t rgba; /* 0xRRGGBBAA */
} rilbed_mark;

/* One call of sense(): the robot, the world now, and what rilbed lends for it. */
typedef struct rilbed_sense_call {
  int64_t t_us; /* simulated time */
  int32_t robot_id;
  double x_m, y_m; /* the robot's pose, field frame */
  double heading_rad;
  double heading_cos, heading_sin; /* cos and sin of heading_rad, as rilbed computed them */
  const rilbed_mobile* mobiles;    /* every robot (this one too) in ID order as added, then every moving obstacle */
  uint32_t mobile_count;
  const void* world; /* rilbed's, for the functions below */
  /* 1 when the floor point (field frame) is on a track: rilbed's own test, indexed. */
  int32_t (*on_track)(const void* world, double x_m, double y_m);
  void* noise;                    /* the robot's noise stream at this instant */
  double (*normal)(void* noise);  /* a standard normal draw from it */
  double (*uniform)(void* noise); /* a uniform draw in [0, 1) from it */
  rilbed_mark* marks;             /* room for mark_capacity marks (the displays'); may be NULL */
  uint32_t mark_capacity;
  uint32_t* mark_count; /* how many the model wrote (starts at 0) */
} rilbed_sense_call;

/* A sensor model: what it is, for rilbed's messages, and
 * its three functions. `error` (of `error_size` bytes) takes a NUL-terminated message
 * when a function fails; rilbed names the library, the mount and the robot around it. */
typedef struct rilbed_sensor_model {
  uint32_t abi_version; /* RILBED_ABI_VERSION */
  const char* name;     /* what a mount names: `name: <name>` */
  const char* summary;  /* one line of what it models */
  const rilbed_sensor_param* params;
  uint32_t param_count;
  uint32_t value_count; /* how many values sense() writes, 1..64 */
  const char* provides; /* NULL, or "track": its values are track readings (0..max, whole) */
  int32_t concurrent;   /* 1: sense() may run for several robots at once (it keeps no mutable state) */
  /* "register": one instance for a mount; NULL (with `error` set) when it cannot. */
  void* (*create)(const rilbed_sensor_setup* setup, char* error, uint32_t error_size);
  /* "model": the robot's readings into values[0..value_count); 0 on success, anything
   * else (with `error` set) ends the run. */
  int32_t (*sense)(const void* model, const rilbed_sense_call* call, double* values, char* error, uint32_t error_size);
  /* "clean-up": once, at the end. */
  void (*destroy)(void* model);
} rilbed_sensor_model;

/* The sensor models a library holds: a list ended by NULL, valid while it is loaded. */
RILBED_EXPORT const rilbed_sensor_model* const* rilbed_sensor_models(void);

#ifdef __cplusplus
}
#endif

#endif /* RILBED_SENSOR_MODEL_H */
