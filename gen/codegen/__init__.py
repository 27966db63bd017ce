"""From a Plan to files: the one description of the generated C interface (abi), the
backends (C, C++/Eigen, FMU, CasADi, the products), and the rendering of their templates."""
