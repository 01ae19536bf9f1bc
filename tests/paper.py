"""The reference study's fixed data: the uncertain coefficients of Table 1 and their intervals."""

# Property and ± interval [% of the nominal] of the paper's Table 1 (wing/fuselage coefficients).
TABLE1 = {
    "CL0": ("aero/uq/CL0", 23.05),
    "CLalpha": ("aero/uq/CLalpha", 5.27),
    "CD0": ("aero/uq/CD0", 12.4),
    "k1": ("aero/uq/k1", 89.16),
    "k2": ("aero/uq/k2", 379.74),
    "Cm0": ("aero/uq/Cm0", 10.46),
    "Cmq": ("aero/uq/Cmq", 0.53),
}


def table1_parameters_yaml(distribution: str = "normal", indent: str = "  ") -> str:
    """The `parameters:` entries of a campaign with Table 1's coefficients and intervals."""
    return "".join(f"{indent}{name}: {{property: {prop}, distribution: {distribution}, interval_pct: {pct}}}\n"
                   for name, (prop, pct) in TABLE1.items())
