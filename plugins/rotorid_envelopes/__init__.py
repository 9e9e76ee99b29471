"""Built-in validation envelopes: MUAD, AEE (data table) and Tischler's mismatch cost J."""
