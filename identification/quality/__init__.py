"""What a result is worth: uncertainty budgets, ISO conformity, and their assembly into the result."""
