"""Products that design with the model: optimal control by direct collocation,
trajectory tracking, model predictive control."""
