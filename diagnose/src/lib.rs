//! Sim-to-real gap: localisation, effect catalogue, attribution, blind benchmark (DESIGN.md §5).
