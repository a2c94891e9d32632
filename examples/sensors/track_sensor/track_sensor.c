/* The floor-track sensor of paper 000 §8 (a photo-reflective emitter/detector pair under
 * the robot that sees reflective tape on the floor), written as a rilbed sensor-model
 * plug-in against rilbed/sensor_model.h alone. It is rilbed's own built-in track sensor
 * (src/environment/track_sensor.cpp) rebuilt outside rilbed: the same footprint, the same
 * threshold and the same noise draws, so a run with it gives the built-in's trajectories
 * byte for byte. docs/write-a-sensor-model.md walks through it.
 *
 * Geometry (§8.1): the element sits Height mm above the floor, its axis inclined
 * Inclination degrees from the vertical towards its mount yaw, and sees a cone of full
 * opening Cone Angle. The cone meets the floor in an ellipse, cut into Precision cells of
 * equal solid angle (each "receives an equal amount of light", Figure 8-2): rings of equal
 * solid-angle steps around the axis, ring j getting cells in proportion to 2j + 1. A cell
 * is its solid-angle centre projected onto the floor.
 *
 * Reading (§8.2): the element triggers when at least Coverage percent of its cells lie on
 * a track; then Max Value (or, with Graded = 1, Max Value times the covered fraction),
 * else 0; plus Gaussian noise of Error Level percent of Max Value; rounded and clamped to
 * [0, Max Value]. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <rilbed/sensor_model.h>

#define PI 3.14159265358979323846

enum { kHeight, kInclination, kConeAngle, kPrecision, kCoverage, kMaxValue, kErrorLevel, kGraded, kParamCount };

/* The keys of its parameter file, as paper 000 §8.2 prints them; the defaults are the
 * paper's example. */
static const rilbed_sensor_param kParams[kParamCount] = {
    {"Height", "mm", "height of the element above the floor", 8.0, 1, 0, 1e-3, 1e3},
    {"Inclination", "deg", "tilt of its axis from the vertical, towards the mount yaw", 45.0, 1, 0, 0.0, 89.0},
    {"Cone Angle", "deg", "full opening of the cone it sees", 30.0, 1, 0, 1e-3, 178.0},
    {"Precision", "", "cells the ellipse is cut into (one track lookup each)", 16.0, 1, 1, 1.0, 4096.0},
    {"Coverage", "%", "share of cells that must be on a track to trigger", 15.0, 1, 0, 0.0, 100.0},
    {"Max Value", "", "full-scale reading", 255.0, 1, 1, 1.0, 1e6},
    {"Error Level", "%", "noise standard deviation, percent of Max Value", 5.0, 1, 0, 0.0, 1000.0},
    {"Graded", "", "1: Max Value times the covered fraction when triggered; 0: Max Value or 0", 0.0, 1, 1, 0.0, 1.0},
};

typedef struct point {
  double x, y;
} point;

/* One mounted element: its cells' floor points in the robot frame, and its numbers. */
typedef struct element {
  point* cells;
  int precision;
  int required; /* least number of covered cells that triggers it */
  double max_value;
  double error_level_percent;
  int graded;
} element;

static double deg_to_rad(double deg) { return deg * PI / 180.0; }

/* Cells per ring: about sqrt(N / pi) rings, ring j weighted 2j + 1, rounded by largest
 * remainder (ties to the inner ring) so that the counts add up to exactly N. Returns the
 * number of rings with cells; `cells` has room for N. */
static int cells_per_ring(int n, int* cells) {
  int rings = (int)lround(sqrt(n / PI));
  if (rings < 1) rings = 1;
  const int weight_sum = rings * rings;
  double* remainder = malloc(sizeof(double) * (size_t)rings);
  int* order = malloc(sizeof(int) * (size_t)rings);
  int given = 0;
  for (int j = 0; j < rings; ++j) {
    const double exact = (double)n * (2 * j + 1) / weight_sum;
    cells[j] = (int)exact;
    given += cells[j];
    remainder[j] = exact - floor(exact);
    order[j] = j;
  }
  /* Largest remainder first; a stable insertion sort keeps equal ones inner ring first. */
  for (int a = 1; a < rings; ++a) {
    const int moving = order[a];
    int b = a;
    while (b > 0 && remainder[order[b - 1]] < remainder[moving]) {
      order[b] = order[b - 1];
      --b;
    }
    order[b] = moving;
  }
  for (int k = 0; given < n; ++k, ++given) ++cells[order[k % rings]];
  free(remainder);
  free(order);
  int kept = 0; /* a ring left without cells (only for tiny N) is dropped */
  for (int j = 0; j < rings; ++j) {
    if (cells[j] > 0) cells[kept++] = cells[j];
  }
  return kept;
}

/* Where a ray at polar angle psi from the axis and azimuth phi (0 towards the lean) meets
 * the floor, robot frame. */
typedef struct lean {
  double h, ca, sa, cy, sy, mount_x, mount_y;
} lean;

static point floor_point(const lean* l, double psi, double phi) {
  const double sp = sin(psi), cp = cos(psi);
  const double rx = cp * l->sa + sp * cos(phi) * l->ca;
  const double ry = sp * sin(phi);
  const double down = cp * l->ca - sp * cos(phi) * l->sa;
  const double t = l->h / down;
  const double lx = t * rx, ly = t * ry;
  const point p = {l->mount_x + l->cy * lx - l->sy * ly, l->mount_y + l->sy * lx + l->cy * ly};
  return p;
}

static void* track_create(const rilbed_sensor_setup* setup, char* error, uint32_t error_size) {
  const double* v = setup->param_values;
  if (v[kInclination] + 0.5 * v[kConeAngle] >= 89.0) {
    snprintf(error, error_size, "Inclination + Cone Angle / 2 must stay below 89 (the cone must meet the floor)");
    return NULL;
  }
  element* e = calloc(1, sizeof(element));
  e->precision = (int)v[kPrecision];
  e->max_value = v[kMaxValue];
  e->error_level_percent = v[kErrorLevel];
  e->graded = v[kGraded] != 0.0;
  const int required = (int)ceil(e->precision * v[kCoverage] / 100.0 - 1e-9);
  e->required = required < 1 ? 1 : required;
  e->cells = malloc(sizeof(point) * (size_t)e->precision);

  const double alpha = deg_to_rad(v[kInclination]);
  const double half_beta = 0.5 * deg_to_rad(v[kConeAngle]);
  const double u_max = 1.0 - cos(half_beta); /* solid angle / 2 pi of the cone */
  const double yaw = deg_to_rad(setup->mount_yaw_deg);
  const lean l = {v[kHeight] * 1e-3, cos(alpha), sin(alpha), cos(yaw), sin(yaw), setup->mount_x_m, setup->mount_y_m};
  int* rings = malloc(sizeof(int) * (size_t)e->precision);
  const int ring_count = cells_per_ring(e->precision, rings);
  int before = 0, next = 0;
  for (int j = 0; j < ring_count; ++j) {
    const int n_j = rings[j];
    const double u_mid = u_max * (before + 0.5 * n_j) / e->precision;
    before += n_j;
    if (j == 0 && n_j == 1) {
      e->cells[next++] = floor_point(&l, 0.0, 0.0); /* the central cap: its centre is the axis */
      continue;
    }
    const double psi = acos(1.0 - u_mid);
    for (int k = 0; k < n_j; ++k) e->cells[next++] = floor_point(&l, psi, 2.0 * PI * (k + 0.5) / n_j);
  }
  free(rings);
  return e;
}

static int32_t track_sense(const void* model, const rilbed_sense_call* call, double* values, char* error,
                           uint32_t error_size) {
  (void)error, (void)error_size;
  const element* e = model;
  const double hx = call->heading_cos, hy = call->heading_sin;
  int covered = 0;
  for (int i = 0; i < e->precision; ++i) {
    const point p = e->cells[i];
    if (call->on_track(call->world, call->x_m + hx * p.x - hy * p.y, call->y_m + hy * p.x + hx * p.y)) ++covered;
  }
  const double max = e->max_value;
  double value = 0.0;
  if (covered >= e->required) value = e->graded ? max * covered / e->precision : max;
  if (e->error_level_percent > 0.0) value += call->normal(call->noise) * e->error_level_percent / 100.0 * max;
  value = round(value);
  values[0] = value < 0.0 ? 0.0 : value > max ? max : value;
  if (covered >= e->required && call->marks && *call->mark_count + 2 <= call->mark_capacity) {
    /* Paper 000 §8.3: two small concentric circles where the element sees the track. */
    double cx = 0.0, cy = 0.0;
    for (int i = 0; i < e->precision; ++i) cx += e->cells[i].x, cy += e->cells[i].y;
    cx /= e->precision, cy /= e->precision;
    const rilbed_mark outer = {RILBED_MARK_CIRCLE, cx, cy, 0.004, 0.0, 0.0, 0x20c0f0ffu};
    const rilbed_mark inner = {RILBED_MARK_CIRCLE, cx, cy, 0.002, 0.0, 0.0, 0x20c0f0ffu};
    call->marks[(*call->mark_count)++] = outer;
    call->marks[(*call->mark_count)++] = inner;
  }
  return 0;
}

static void track_destroy(void* model) {
  element* e = model;
  free(e->cells);
  free(e);
}

RILBED_DEFINE_PLUGIN();

static const rilbed_sensor_model track_element = {
    RILBED_ABI_VERSION,
    "track_element",
    "one photo-reflective element of paper 000's floor-track sensor: Max Value when enough of its cone's footprint "
    "is on tape",
    kParams,
    kParamCount,
    1,       /* one value: the element's reading */
    "track", /* read by controllers as track readings, after the robot's built-in elements */
    1,       /* no state: robots may sense at once */
    track_create,
    track_sense,
    track_destroy};

const rilbed_sensor_model* const* rilbed_sensor_models(void) {
  static const rilbed_sensor_model* const list[] = {&track_element, NULL};
  return list;
}
