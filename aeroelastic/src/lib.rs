//! Structure, aerodynamic models, time integration, flutter, LCO and the virtual wind tunnel
//! (DESIGN.md §4). Built on `identify` for data sets and Eq. 19 types.
