"""State estimation from the model: extended and unscented Kalman filters
over the model's own discrete step, in C (gen.EKF, gen.UKF).

    filters   the faces: EKF, UKF, FilterResult
    model     the filter's model (constants to estimate promoted to
              coordinates), the measurements, the library's ProductPlan
    loop      the filter feeding a controller in sim.simulate (in C)
    firmware  to_c (a firmware module and a standalone program), footprint
"""
from .filters import (ACCEPTED, DEGENERATE, EKF, GATED, MISSING, UKF, FilterResult)

__all__ = ["EKF", "UKF", "FilterResult", "ACCEPTED", "GATED", "MISSING", "DEGENERATE"]
