/* A sensor-model plug-in library for the loader's and the world's tests
 * (test_library_sensor_models.cpp), built against the SDK's headers only:
 *   "beacon_range"  two values: the distance from the robot to a point given by its
 *                   parameters, and how many mobile objects it was told of; plus one
 *                   uniform draw times its Noise parameter
 *   "failing"       a reading that fails at and after its "Fail At" (ms)
 *   "cone"          provides "track": one value, its "Level" parameter
 * and actuator models:
 *   "reverse"       drives each wheel backwards at its "Gain" times the command; counts nothing
 *   "runaway"       fails at and after its "Fail At" (ms), and before that gives NaN when the
 *                   command is 99 units */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <rilbed/actuator_model.h>
#include <rilbed/sensor_model.h>

typedef struct point_model {
  double x_m, y_m, noise, mount_x_m;
} point_model;

static const rilbed_sensor_param kRangeParams[] = {
    {"Target X", "m", "the point's x", 0.0, 0, 0, -100.0, 100.0},
    {"Target Y", "m", "the point's y", 0.0, 1, 0, -100.0, 100.0},
    {"Noise", "m", "uniform noise amplitude", 0.0, 1, 0, 0.0, 1.0},
};

static void* range_create(const rilbed_sensor_setup* setup, char* error, uint32_t error_size) {
  if (setup->world->width_m <= 0.0) {
    snprintf(error, error_size, "a field without width");
    return NULL;
  }
  if (setup->param_values[0] == 99.0) {
    snprintf(error, error_size, "target x 99 is refused by this model");
    return NULL;
  }
  point_model* m = malloc(sizeof(point_model));
  m->x_m = setup->param_values[0];
  m->y_m = setup->param_values[1];
  m->noise = setup->param_values[2];
  m->mount_x_m = setup->mount_x_m;
  return m;
}

static int32_t range_sense(const void* model, const rilbed_sense_call* call, double* values, char* error,
                           uint32_t error_size) {
  (void)error, (void)error_size;
  const point_model* m = model;
  values[0] = hypot(call->x_m - m->x_m, call->y_m - m->y_m) + m->noise * call->uniform(call->noise);
  values[1] = call->mobile_count;
  if (call->marks && *call->mark_count + 3 <= call->mark_capacity) {
    /* A circle at its mount, a line 10 cm ahead, and one that no display could draw. */
    const rilbed_mark circle = {RILBED_MARK_CIRCLE, m->mount_x_m, 0.0, 0.01, 0.0, 0.0, 0xff0000ffu};
    const rilbed_mark ahead = {RILBED_MARK_LINE, 0.0, 0.0, 0.0, 0.1, 0.0, 0x00ff00ffu};
    const rilbed_mark junk = {RILBED_MARK_CIRCLE, NAN, 0.0, 0.01, 0.0, 0.0, 0u};
    call->marks[(*call->mark_count)++] = circle;
    call->marks[(*call->mark_count)++] = ahead;
    call->marks[(*call->mark_count)++] = junk;
  }
  return 0;
}

static void free_model(void* model) { free(model); }

static const rilbed_sensor_param kFailParams[] = {{"Fail At", "ms", "when it fails", 0.0, 0, 1, 0.0, 1e9}};

static void* fail_create(const rilbed_sensor_setup* setup, char* error, uint32_t error_size) {
  (void)error, (void)error_size;
  double* at = malloc(sizeof(double));
  *at = setup->param_values[0];
  return at;
}

static int32_t fail_sense(const void* model, const rilbed_sense_call* call, double* values, char* error,
                          uint32_t error_size) {
  if ((double)call->t_us >= *(const double*)model * 1000.0) {
    snprintf(error, error_size, "the lens is cracked");
    return 1;
  }
  values[0] = 1.0;
  return 0;
}

static const rilbed_sensor_param kConeParams[] = {{"Level", "", "its reading", 7.0, 1, 1, 0.0, 1000.0}};

static int32_t cone_sense(const void* model, const rilbed_sense_call* call, double* values, char* error,
                          uint32_t error_size) {
  (void)call, (void)error, (void)error_size;
  values[0] = *(const double*)model;
  return 0;
}

RILBED_DEFINE_PLUGIN();

static const rilbed_sensor_model beacon_range = {
    RILBED_ABI_VERSION, "beacon_range", "distance to a point", kRangeParams, 3, 2, NULL, 1, range_create,
    range_sense,        free_model};
static const rilbed_sensor_model failing = {
    RILBED_ABI_VERSION, "failing",  "fails at its time", kFailParams, 1, 1, NULL, 0,
    fail_create,        fail_sense, free_model};
static const rilbed_sensor_model cone = {
    RILBED_ABI_VERSION, "cone",    "a track reading of its level", kConeParams, 1, 1, "track", 1, fail_create,
    cone_sense,         free_model};

static const rilbed_actuator_param kReverseParams[] = {{"Gain", "", "speed per command", 1.0, 1, 0, 0.0, 10.0}};

static void* reverse_create(const rilbed_actuator_setup* setup, char* error, uint32_t error_size) {
  if (setup->robot_id == 13) {
    snprintf(error, error_size, "robot 13 has no wheels");
    return NULL;
  }
  double* gain = malloc(sizeof(double));
  *gain = setup->param_values[0] * (setup->wheel_base_m > 0.0 ? 1.0 : 0.0);
  return gain;
}

static int32_t reverse_drive(void* model, const rilbed_drive_call* call, rilbed_drive_output* out, char* error,
                             uint32_t error_size) {
  (void)error, (void)error_size;
  const double gain = *(const double*)model;
  out->left_mps = -gain * call->left_command_mps;
  out->right_mps = -gain * call->right_command_mps;
  out->left_counted_mps = out->right_counted_mps = 0.0;
  return 0;
}

static int32_t runaway_drive(void* model, const rilbed_drive_call* call, rilbed_drive_output* out, char* error,
                             uint32_t error_size) {
  if ((double)call->t_us >= *(const double*)model * 1000.0) {
    snprintf(error, error_size, "the motor burnt out");
    return 1;
  }
  if (call->left_units == 99) out->left_mps = NAN;
  return 0;
}

static void* runaway_create(const rilbed_actuator_setup* setup, char* error, uint32_t error_size) {
  (void)error, (void)error_size;
  double* at = malloc(sizeof(double));
  *at = setup->param_values[0];
  return at;
}

static const rilbed_actuator_model reverse = {RILBED_ABI_VERSION, "reverse",     "backwards", kReverseParams, 1, 1,
                                              reverse_create,     reverse_drive, free_model};
static const rilbed_actuator_model runaway = {RILBED_ABI_VERSION, "runaway",     "fails",   kFailParams, 1, 0,
                                              runaway_create,     runaway_drive, free_model};

const rilbed_actuator_model* const* rilbed_actuator_models(void) {
  static const rilbed_actuator_model* const list[] = {&reverse, &runaway, NULL};
  return list;
}

const rilbed_sensor_model* const* rilbed_sensor_models(void) {
  static const rilbed_sensor_model* const list[] = {&beacon_range, &failing, &cone, NULL};
  return list;
}
