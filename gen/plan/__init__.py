"""From a Model to a Plan: kernels with one joint CSE each and their Jacobians, the
mass-matrix structure and the acceleration solver, symbolic linearization, structural
dependencies."""
