"""The numpy face of a loaded model: the Simulator, run options, solutions, inputs and
controllers, events, ensembles, Ctrl-C."""
