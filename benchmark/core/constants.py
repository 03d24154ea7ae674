"""Physical constants shared by the problems."""

#: Inferred absolute zero of copper resistance, deg C: ``R(theta) ~ (COPPER_INFERRED_ZERO_C + theta)``.
COPPER_INFERRED_ZERO_C = 234.5
