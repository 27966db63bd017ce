/*
 * gen_host_interrupt.c - the SIGINT relay of eomgen's Python host module
 * (gen_host_interrupt.h). Its state is the process's: the slots of the
 * calls in progress and the handler it chains to. A signal handler only
 * writes sig_atomic_t flags and calls the handler it replaced.
 */
#include <signal.h>
#include <string.h>

#define EOMGEN_INTERRUPT_SLOTS 64

/* the runtime reads a flag through an int pointer */
typedef char eomgen_interrupt_int_flags_[sizeof(sig_atomic_t) == sizeof(int) ? 1 : -1];

static volatile sig_atomic_t eomgen_interrupt_flags_[EOMGEN_INTERRUPT_SLOTS];
static volatile sig_atomic_t eomgen_interrupt_count_;

/* the relay needs sigaction (POSIX: the module is compiled after Python.h,
 * which asks for it) and the GCC/Clang atomic builtins; elsewhere no call is
 * armed and Ctrl-C acts when the call returns */
#if defined(SA_SIGINFO) && (defined(__GNUC__) || defined(__clang__))
static int eomgen_interrupt_used_[EOMGEN_INTERRUPT_SLOTS];
static int eomgen_interrupt_lock_;
static struct sigaction eomgen_interrupt_prev_;
/* the flags of the replaced handler kept (the alternate stack, restart) */
#if defined(SA_ONSTACK) && defined(SA_RESTART)
#define EOMGEN_INTERRUPT_KEEP_ (SA_ONSTACK | SA_RESTART)
#else
#define EOMGEN_INTERRUPT_KEEP_ 0
#endif

static void eomgen_interrupt_relay_(int sig, siginfo_t *info, void *uctx)
{
    int i;
    for (i = 0; i < EOMGEN_INTERRUPT_SLOTS; ++i) eomgen_interrupt_flags_[i] = 1;
    eomgen_interrupt_count_ = eomgen_interrupt_count_ + 1;
    if (eomgen_interrupt_prev_.sa_flags & SA_SIGINFO) {
        if (eomgen_interrupt_prev_.sa_sigaction)
            eomgen_interrupt_prev_.sa_sigaction(sig, info, uctx);
    } else if (eomgen_interrupt_prev_.sa_handler != SIG_DFL &&
               eomgen_interrupt_prev_.sa_handler != SIG_IGN) {
        eomgen_interrupt_prev_.sa_handler(sig);
    }
}

/* the relay in place (under the lock): 0, or -1 when SIGINT is not handled
 * by a function (ignored, default) */
static int eomgen_interrupt_install_(void)
{
    struct sigaction cur, act;
    if (sigaction(SIGINT, NULL, &cur) != 0) return -1;
    if ((cur.sa_flags & SA_SIGINFO) && cur.sa_sigaction == eomgen_interrupt_relay_) return 0;
    if (!(cur.sa_flags & SA_SIGINFO) && (cur.sa_handler == SIG_DFL || cur.sa_handler == SIG_IGN))
        return -1;
    eomgen_interrupt_prev_ = cur;
    memset(&act, 0, sizeof act);
    act.sa_sigaction = eomgen_interrupt_relay_;
    act.sa_mask = cur.sa_mask;
    act.sa_flags = SA_SIGINFO | (cur.sa_flags & EOMGEN_INTERRUPT_KEEP_);
    return sigaction(SIGINT, &act, NULL) == 0 ? 0 : -1;
}

int eomgen_interrupt_arm(void)
{
    int i, slot = -1;
    while (__sync_lock_test_and_set(&eomgen_interrupt_lock_, 1)) {
    }
    if (eomgen_interrupt_install_() == 0) {
        for (i = 0; i < EOMGEN_INTERRUPT_SLOTS; ++i)
            if (!eomgen_interrupt_used_[i]) {
                eomgen_interrupt_used_[i] = 1;
                eomgen_interrupt_flags_[i] = 0;
                slot = i;
                break;
            }
    }
    __sync_lock_release(&eomgen_interrupt_lock_);
    return slot;
}

int eomgen_interrupt_release(int slot)
{
    int hit;
    if (slot < 0 || slot >= EOMGEN_INTERRUPT_SLOTS) return 0;
    while (__sync_lock_test_and_set(&eomgen_interrupt_lock_, 1)) {
    }
    hit = eomgen_interrupt_flags_[slot] != 0;
    eomgen_interrupt_used_[slot] = 0;
    __sync_lock_release(&eomgen_interrupt_lock_);
    return hit;
}
#else
int eomgen_interrupt_arm(void) { return -1; }
int eomgen_interrupt_release(int slot) { (void)slot; return 0; }
#endif

int *eomgen_interrupt_flag(int slot)
{
    if (slot < 0 || slot >= EOMGEN_INTERRUPT_SLOTS) return NULL;
    return (int *)&eomgen_interrupt_flags_[slot];
}

/* the counter the batch loops watch: this module's, or the owner's */
static const volatile sig_atomic_t *eomgen_interrupt_watch_ = &eomgen_interrupt_count_;

long eomgen_interrupt_count(void)
{
    return (long)*eomgen_interrupt_watch_;
}

void *eomgen_interrupt_counter(void)
{
    return (void *)&eomgen_interrupt_count_;
}

void eomgen_interrupt_follow(void *counter)
{
    if (counter) eomgen_interrupt_watch_ = (const volatile sig_atomic_t *)counter;
}
