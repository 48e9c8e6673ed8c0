"""Closed-loop experiments over Modbus, run through one executor (local processes or a Dask cluster),
and the Nelder-Mead search of the controller parameters on them (`thermost optimise`)."""
