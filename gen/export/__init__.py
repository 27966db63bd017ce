"""Products that hand the model to other tools: FMUs, CasADi functions, the PyDy
drop-in, verification against sympy."""
