/*
 * irrcache/version.h — the library's version: compile-time macros and ic_version() at run time.
 *
 * The macros are the version of the headers a program was compiled against; ic_version() is the
 * version of the library it runs with. They match project(irrcache VERSION …) in CMakeLists.txt
 * (configuring refuses a mismatch).
 *
 *   #if IRRCACHE_VERSION_NUMBER >= IRRCACHE_MAKE_VERSION(0, 1, 0)   ... #endif
 *   printf("irrcache %s\n", ic_version());
 */
#ifndef IRRCACHE_VERSION_H
#define IRRCACHE_VERSION_H

#ifdef __cplusplus
extern "C" {
#endif

#define IRRCACHE_VERSION_MAJOR 0
#define IRRCACHE_VERSION_MINOR 5
#define IRRCACHE_VERSION_PATCH 0

/* One comparable number per version: major·10000 + minor·100 + patch. */
#define IRRCACHE_MAKE_VERSION(major, minor, patch) ((major) * 10000 + (minor) * 100 + (patch))
#define IRRCACHE_VERSION_NUMBER \
    IRRCACHE_MAKE_VERSION(IRRCACHE_VERSION_MAJOR, IRRCACHE_VERSION_MINOR, IRRCACHE_VERSION_PATCH)

#define IRRCACHE_VERSION_STRINGIFY_(x) #x
#define IRRCACHE_VERSION_STRINGIFY(x) IRRCACHE_VERSION_STRINGIFY_(x)
/* "MAJOR.MINOR.PATCH" */
#define IRRCACHE_VERSION_STRING                                                            \
    IRRCACHE_VERSION_STRINGIFY(IRRCACHE_VERSION_MAJOR) "." IRRCACHE_VERSION_STRINGIFY(    \
        IRRCACHE_VERSION_MINOR) "." IRRCACHE_VERSION_STRINGIFY(IRRCACHE_VERSION_PATCH)

/* The version of the library linked in, "MAJOR.MINOR.PATCH"; a static string, never NULL. */
const char *ic_version(void);

#ifdef __cplusplus
}
#endif
#endif
