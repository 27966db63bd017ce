"""C identifiers for eomgen: the rules a model name (the C prefix) must
follow, the C keywords and C library names it must not shadow, and the
spelling of sympy names (any character) as unique C identifiers.

No sympy here: these work on plain strings.
"""
from __future__ import annotations

import re

from .errors import ModelError

__all__ = ["validate_name", "c_name", "c_names", "C_KEYWORDS", "C_LIBRARY_NAMES"]

# C keywords (C99/C11/C23) and the C library / libm names a prefix must not
# shadow (a prefix is followed by "_" in every emitted name, but the prefix
# alone is used as the header guard stem and the cffi module stem).
C_KEYWORDS = frozenset("""
auto break case char const continue default do double else enum extern float for
goto if inline int long register restrict return short signed sizeof static
struct switch typedef union unsigned void volatile while _Bool _Complex
_Imaginary _Alignas _Alignof _Atomic _Generic _Noreturn _Static_assert
_Thread_local alignas alignof bool constexpr false nullptr static_assert
thread_local true typeof typeof_unqual asm fortran
""".split())
C_LIBRARY_NAMES = frozenset("""
abs acos acosh asin asinh atan atan2 atanh cbrt ceil copysign cos cosh erf erfc
exp exp2 expm1 fabs fdim floor fma fmax fmin fmod frexp hypot ilogb ldexp lgamma
llrint llround log log10 log1p log2 logb lrint lround modf nan nearbyint
nextafter nexttoward pow remainder remquo rint round scalbln scalbn sin sinh
sqrt tan tanh tgamma trunc j0 j1 jn y0 y1 yn gamma signgam index rindex time
main malloc calloc realloc free exit abort printf fprintf sprintf snprintf puts
putchar memcpy memset memmove strlen strcpy errno assert math stdio stdlib
string float double int long short char signed unsigned int8_t int16_t int32_t
int64_t uint8_t uint16_t uint32_t uint64_t size_t NULL EOF
""".split())
_NAME_RE = re.compile(r"^[a-z][a-z0-9_]*$")


def validate_name(name: str) -> str:
    """Check a model name used as the C prefix; return it or raise."""
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise ModelError(
            f"model name {name!r} is not a valid C prefix: use lower-case letters, "
            "digits and '_', starting with a letter (for example 'pendulum_kane')")
    if name in C_KEYWORDS or name in C_LIBRARY_NAMES:
        raise ModelError(
            f"model name {name!r} is a C keyword or C library name; choose another "
            "(for example 'my_" + name + "')")
    if len(name) > 40:
        raise ModelError(f"model name {name!r} is longer than 40 characters")
    if "__" in name or name.endswith("_"):
        raise ModelError(f"model name {name!r} must not contain '__' or end with '_'")
    return name


def c_name(label: str) -> str:
    """An identifier for a sympy name: letters, digits and '_' kept, a prime
    becomes '_p', other ASCII punctuation '_', other characters 'u' + their
    hex code point; a leading digit gets a leading '_'."""
    out = []
    for ch in label:
        if ch.isascii() and (ch.isalnum() or ch == "_"):
            out.append(ch)
        elif ch == "'":
            out.append("_p")
        elif ch.isascii():
            if not out or out[-1] != "_":       # one '_' per run of punctuation
                out.append("_")
        else:
            out.append(f"u{ord(ch):04x}")
    name = "".join(out).strip("_") or "s"
    if name[0].isdigit():
        name = "_" + name
    return name


def c_names(labels):
    """c_name of each label, made unique (suffix _2, _3, ...) in order."""
    seen = set()
    out = []
    for label in labels:
        base = c_name(label)
        name, k = base, 2
        while name in seen:
            name = f"{base}_{k}"
            k += 1
        seen.add(name)
        out.append(name)
    return out
