"""From sympy objects to the canonical Model: the adapters (KanesMethod,
LagrangesMethod, System, matrices), reactions, hybrid declarations, the recursive
formulation of a System's joint tree."""
