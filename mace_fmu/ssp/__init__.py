"""SSP 1.0 (System Structure and Parameterization): parameter sets as SSV files, FMUs wired into SSP archives."""

from mace_fmu.ssp.package import SspComponent, SspConnection, schema_problems, system_structure, write_ssp
from mace_fmu.ssp.ssv import (FrequencyBound, SsvContent, parameter_set_from_ssv, parameter_set_to_ssv, read_parameter_ssv,
                              write_parameter_ssv)

__all__ = ["FrequencyBound", "SspComponent", "SspConnection", "SsvContent", "parameter_set_from_ssv", "parameter_set_to_ssv",
           "read_parameter_ssv", "schema_problems", "system_structure", "write_parameter_ssv", "write_ssp"]
