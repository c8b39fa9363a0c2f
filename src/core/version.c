/*
 * version.c — ic_version(): the version the library was built as (irrcache/version.h). It lives in
 * the core so that every irrcache library, the cache alone included, reports it.
 */
#include "irrcache/version.h"

const char *ic_version(void)
{
    return IRRCACHE_VERSION_STRING;
}
