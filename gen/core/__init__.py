"""The ground floor: errors and the runtime's status table, the build cache, where the
templates and the C runtime live, C names, the optional dependencies. Imports nothing of gen."""
