/* gen_rt_config.h - runtime configuration written by eomgen. Do not edit. */
#ifndef GEN_RT_CONFIG_H
#define GEN_RT_CONFIG_H
#endif
