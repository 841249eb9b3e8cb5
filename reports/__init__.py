"""Material cards, plots and test reports."""
