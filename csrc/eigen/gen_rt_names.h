/*
 * gen_rt_names.h - the C runtime's external names for a second scalar type.
 *
 * The C++/Eigen backend links the model and the runtime twice, once per
 * scalar type (float and double, as BLAS has s and d), so that one program
 * can use both through the typed face. Its gen_rt_config.h includes this
 * header in the translation units of the second copy (GEN_RT_ALT_REAL
 * defined): every function the runtime defines gets the prefix gen_rt_s_
 * (float) or gen_rt_d_ (double); the copy of the build's own scalar type
 * keeps the plain names, exactly as the C backend compiles it.
 *
 * A runtime function missing here is defined twice in an Eigen build's
 * library, which fails its link (gen.compile links every object into one
 * shared library; tests/features/test_eigen.py also checks the objects' names).
 * Types and static functions need nothing; the runtime's private functions
 * (gen_rt_private.h: external, hidden) are renamed as well.
 */
#ifndef GEN_RT_NAMES_H
#define GEN_RT_NAMES_H

#ifdef GEN_RT_REAL_FLOAT
#define GEN_RT_NAME_(n) gen_rt_s_##n
#else
#define GEN_RT_NAME_(n) gen_rt_d_##n
#endif

#define gen_rt_accel_kkt GEN_RT_NAME_(accel_kkt)
#define gen_rt_accel_partitioned GEN_RT_NAME_(accel_partitioned)
#define gen_rt_accel_reactions GEN_RT_NAME_(accel_reactions)
#define gen_rt_all_finite GEN_RT_NAME_(all_finite)
#define gen_rt_c2d_zoh GEN_RT_NAME_(c2d_zoh)
#define gen_rt_chol_factor GEN_RT_NAME_(chol_factor)
#define gen_rt_chol_solve GEN_RT_NAME_(chol_solve)
#define gen_rt_dopri5_dense GEN_RT_NAME_(dopri5_dense)
#define gen_rt_dopri5_trial GEN_RT_NAME_(dopri5_trial)
#define gen_rt_engine_dense GEN_RT_NAME_(engine_dense)
#define gen_rt_engine_init GEN_RT_NAME_(engine_init)
#define gen_rt_engine_method_ok GEN_RT_NAME_(engine_method_ok)
#define gen_rt_engine_project GEN_RT_NAME_(engine_project)
#define gen_rt_engine_step GEN_RT_NAME_(engine_step)
#define gen_rt_err_norm GEN_RT_NAME_(err_norm)
#define gen_rt_events_check GEN_RT_NAME_(events_check)
#define gen_rt_events_start GEN_RT_NAME_(events_start)
#define gen_rt_events_step GEN_RT_NAME_(events_step)
#define gen_rt_expm GEN_RT_NAME_(expm)
#define gen_rt_hermite GEN_RT_NAME_(hermite)
#define gen_rt_hybrid_crossed GEN_RT_NAME_(hybrid_crossed)
#define gen_rt_hybrid_impulse GEN_RT_NAME_(hybrid_impulse)
#define gen_rt_hybrid_jump GEN_RT_NAME_(hybrid_jump)
#define gen_rt_hybrid_penetrated GEN_RT_NAME_(hybrid_penetrated)
#define gen_rt_hybrid_rates GEN_RT_NAME_(hybrid_rates)
#define gen_rt_hybrid_reset GEN_RT_NAME_(hybrid_reset)
#define gen_rt_hybrid_rhs GEN_RT_NAME_(hybrid_rhs)
#define gen_rt_hybrid_values GEN_RT_NAME_(hybrid_values)
#define gen_rt_input_at GEN_RT_NAME_(input_at)
#define gen_rt_input_check GEN_RT_NAME_(input_check)
#define gen_rt_input_gain_row GEN_RT_NAME_(input_gain_row)
#define gen_rt_input_next_break GEN_RT_NAME_(input_next_break)
#define gen_rt_input_now GEN_RT_NAME_(input_now)
#define gen_rt_input_sample GEN_RT_NAME_(input_sample)
#define gen_rt_kkt_matrix GEN_RT_NAME_(kkt_matrix)
#define gen_rt_linearize GEN_RT_NAME_(linearize)
#define gen_rt_lu_factor GEN_RT_NAME_(lu_factor)
#define gen_rt_lu_solve GEN_RT_NAME_(lu_solve)
#define gen_rt_lu_solve_t GEN_RT_NAME_(lu_solve_t)
#define gen_rt_matmul GEN_RT_NAME_(matmul)
#define gen_rt_max_abs GEN_RT_NAME_(max_abs)
#define gen_rt_min_norm_correct GEN_RT_NAME_(min_norm_correct)
#define gen_rt_model_advance GEN_RT_NAME_(model_advance)
#define gen_rt_model_consistent_state GEN_RT_NAME_(model_consistent_state)
#define gen_rt_model_eval_auxiliary_forces GEN_RT_NAME_(model_eval_auxiliary_forces)
#define gen_rt_model_eval_constraint_jacobian GEN_RT_NAME_(model_eval_constraint_jacobian)
#define gen_rt_model_eval_constraints GEN_RT_NAME_(model_eval_constraints)
#define gen_rt_model_eval_energy GEN_RT_NAME_(model_eval_energy)
#define gen_rt_model_eval_forcing GEN_RT_NAME_(model_eval_forcing)
#define gen_rt_model_eval_hybrid GEN_RT_NAME_(model_eval_hybrid)
#define gen_rt_model_eval_input GEN_RT_NAME_(model_eval_input)
#define gen_rt_model_eval_kinematics GEN_RT_NAME_(model_eval_kinematics)
#define gen_rt_model_eval_mass_matrix GEN_RT_NAME_(model_eval_mass_matrix)
#define gen_rt_model_eval_outputs GEN_RT_NAME_(model_eval_outputs)
#define gen_rt_model_eval_rhs GEN_RT_NAME_(model_eval_rhs)
#define gen_rt_model_eval_velocity_constraint_matrix GEN_RT_NAME_(model_eval_velocity_constraint_matrix)
#define gen_rt_model_eval_velocity_constraints GEN_RT_NAME_(model_eval_velocity_constraints)
#define gen_rt_model_jacobian GEN_RT_NAME_(model_jacobian)
#define gen_rt_model_linearize GEN_RT_NAME_(model_linearize)
#define gen_rt_model_linearize_discrete GEN_RT_NAME_(model_linearize_discrete)
#define gen_rt_model_linearize_outputs GEN_RT_NAME_(model_linearize_outputs)
#define gen_rt_model_project GEN_RT_NAME_(model_project)
#define gen_rt_model_rhs GEN_RT_NAME_(model_rhs)
#define gen_rt_model_simulate GEN_RT_NAME_(model_simulate)
#define gen_rt_model_simulate_events GEN_RT_NAME_(model_simulate_events)
#define gen_rt_model_simulate_input GEN_RT_NAME_(model_simulate_input)
#define gen_rt_model_step_rk4 GEN_RT_NAME_(model_step_rk4)
#define gen_rt_model_state_map GEN_RT_NAME_(model_state_map)
#define gen_rt_model_step_sensitivity GEN_RT_NAME_(model_step_sensitivity)
#define gen_rt_reactions_columns GEN_RT_NAME_(reactions_columns)
#define gen_rt_reactions_lin GEN_RT_NAME_(reactions_lin)
#define gen_rt_rk4_step GEN_RT_NAME_(rk4_step)
#define gen_rt_rodas4_trial GEN_RT_NAME_(rodas4_trial)
#define gen_rt_sim_ctx_init GEN_RT_NAME_(sim_ctx_init)
#define gen_rt_simulate_rows GEN_RT_NAME_(simulate_rows)
#define gen_rt_simulate_rows_kept GEN_RT_NAME_(simulate_rows_kept)
#define gen_rt_status_message GEN_RT_NAME_(status_message)

#endif /* GEN_RT_NAMES_H */
