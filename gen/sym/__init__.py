"""Expression graphs: differentiation (non-smooth functions almost everywhere),
evaluation in floats, the C printers of kernels. Over core only."""
