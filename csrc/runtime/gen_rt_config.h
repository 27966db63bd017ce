/* gen_rt_config.h - build configuration of the runtime. The generator
 * writes its own copy next to generated models; this default is double. */
#ifndef GEN_RT_CONFIG_H
#define GEN_RT_CONFIG_H
/* #define GEN_RT_REAL_FLOAT */
#endif
