"""Robustness of a compensator designed on the nominal 0-g model: closed around the 0-g FMU over its
declared parameter bounds (corners and a seeded Monte Carlo sample), on the Dask runner."""
