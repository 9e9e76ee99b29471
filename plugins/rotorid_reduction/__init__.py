"""Built-in model-reduction criteria: normalised insensitivity and Cramér-Rao bound."""
