/* What every rilbed plug-in library shares, whatever it holds (controllers, sensor
 * models): the ABI version it was built against, the visibility of what it exports, and
 * the functions rilbed lends it when it loads it.
 *
 * A plug-in library writes RILBED_DEFINE_PLUGIN() once, in one of its C or C++ source
 * files, at file scope. rilbed's loader then
 *   1. opens the library (dlopen, every symbol resolved at once),
 *   2. calls rilbed_abi_version() and refuses a library whose version is not its own,
 *      naming the library and both versions,
 *   3. calls rilbed_plugin_bind() with its host functions (rilbed_peek and rilbed_poke go
 *      through them),
 *   4. asks for the lists the library exports (rilbed_controllers(),
 *      rilbed_controller_classes(), ...; see rilbed_controller.h).
 * The library stays loaded while anything it made is in use.
 *
 * Everything that crosses between rilbed and a library is C: plain structs, C strings,
 * function pointers. A library may be built by another compiler or another C++ standard
 * library than rilbed's, in C or in C++ (rilbed/controller.hpp wraps these structs). */
#ifndef RILBED_PLUGIN_H
#define RILBED_PLUGIN_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The version of the structs and functions in rilbed's SDK headers. It changes whenever
 * one of them changes in a way that a library built against the old headers would
 * misread; rilbed loads only libraries built with its own. */
#define RILBED_ABI_VERSION 1u

/* Marks a symbol a library exports to rilbed (libraries may hide the rest, e.g. with
 * -fvisibility=hidden). */
#if defined(__GNUC__) || defined(__clang__)
#define RILBED_EXPORT __attribute__((visibility("default")))
#define RILBED_HIDDEN __attribute__((visibility("hidden")))
#else
#define RILBED_EXPORT
#define RILBED_HIDDEN
#endif

/* What rilbed lends a library: the register map of the robot whose controller is being
 * called (rilbed_controller.h). Valid from rilbed_plugin_bind() until the library is
 * unloaded. */
typedef struct rilbed_host {
  uint32_t abi_version;                          /* RILBED_ABI_VERSION of rilbed itself */
  int32_t (*peek)(uint32_t address);             /* rilbed_peek() */
  void (*poke)(uint32_t address, int32_t value); /* rilbed_poke() */
} rilbed_host;

/* The ABI version the library was built against (RILBED_DEFINE_PLUGIN defines it). */
RILBED_EXPORT uint32_t rilbed_abi_version(void);
/* Called once by the loader, before anything else of the library is used. */
RILBED_EXPORT void rilbed_plugin_bind(const rilbed_host* host);

/* The library's own copy of the host functions, set by rilbed_plugin_bind(). */
extern RILBED_HIDDEN const rilbed_host* rilbed_plugin_host;

/* Defines rilbed_abi_version(), rilbed_plugin_bind() and the library's own rilbed_peek()
 * and rilbed_poke(), which call rilbed's (hidden, so that two libraries never take each
 * other's). Write it once per library, at file scope. */
#define RILBED_DEFINE_PLUGIN()                                                                  \
  RILBED_HIDDEN const rilbed_host* rilbed_plugin_host = 0;                                      \
  RILBED_EXPORT uint32_t rilbed_abi_version(void) { return RILBED_ABI_VERSION; }                \
  RILBED_EXPORT void rilbed_plugin_bind(const rilbed_host* host) { rilbed_plugin_host = host; } \
  RILBED_HIDDEN int32_t rilbed_peek(uint32_t address) {                                         \
    return rilbed_plugin_host ? rilbed_plugin_host->peek(address) : 0;                          \
  }                                                                                             \
  RILBED_HIDDEN void rilbed_poke(uint32_t address, int32_t value) {                             \
    if (rilbed_plugin_host) rilbed_plugin_host->poke(address, value);                           \
  }                                                                                             \
  typedef int rilbed_plugin_defined_ /* so that the macro is used as a statement: `RILBED_DEFINE_PLUGIN();` */

#ifdef __cplusplus
}
#endif

#endif /* RILBED_PLUGIN_H */
