/* gen_rt_config.h - runtime configuration written by eomgen (C++/Eigen
 * backend). Do not edit.
 *
 * The library holds the model and the runtime twice: for double, the
 * build's scalar type (the C API pendulum_kane_*, the runtime's plain names), and
 * in the translation units compiled with GEN_RT_ALT_REAL defined, for float
 * (the model pendulum_kane_s_*, the runtime's names prefixed by gen_rt_names.h).
 */
#ifndef GEN_RT_CONFIG_H
#define GEN_RT_CONFIG_H
#if defined(GEN_RT_ALT_REAL)
#define GEN_RT_REAL_FLOAT
#endif
#ifdef GEN_RT_ALT_REAL
#include "gen_rt_names.h"
#endif
#endif
