/*
 * gen_host_interrupt.h - Ctrl-C during the long calls of eomgen's Python
 * host module (gen/sim/interrupt.py). Hand-written; plain C declarations (also
 * the module's cffi cdef).
 *
 * The C runtime knows nothing of signals: a simulation stops when the
 * cancellation flag its caller owns (sim_options.cancel) becomes nonzero.
 * This relay is the caller's side in the Python host: a SIGINT handler that
 * sets the flag of every call in progress, then calls the handler it
 * replaced (Python's own, which raises KeyboardInterrupt once the call
 * returns). It is installed by the first armed call (again after Python
 * replaced it), only over a handler that is a function (a SIGINT ignored or
 * left to its default stays so).
 */

/* a slot for one call: its flag, cleared, which SIGINT sets; -1 when there
 * is no relay (SIGINT ignored or default, no sigaction, all slots taken) */
int eomgen_interrupt_arm(void);
/* the flag of a slot (for sim_options.cancel) */
int *eomgen_interrupt_flag(int slot);
/* frees a slot; returns its flag (nonzero: a SIGINT came during the call) */
int eomgen_interrupt_release(int slot);
/* the SIGINTs relayed so far (by the relay this module follows): the batch
 * loops stop when it changes */
long eomgen_interrupt_count(void);
/* One relay per process: each host module (double, float) has its own
 * code, and two relays chained over each other could call each other
 * forever. The Python side arms only the first module's; another module
 * follows its counter (eomgen_interrupt_counter of the owner) for its
 * batch loops, and its runs take the owner's flags. */
void *eomgen_interrupt_counter(void);
void eomgen_interrupt_follow(void *counter);
