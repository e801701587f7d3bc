"""Layer 5: typer commands and rich rendering only."""
