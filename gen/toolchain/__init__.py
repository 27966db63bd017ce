"""From files to loaded code: compiling and linking into the content-keyed cache,
the Python host module and the loading of libraries, the embedded footprint. The only
place that runs a compiler or opens a shared library."""
