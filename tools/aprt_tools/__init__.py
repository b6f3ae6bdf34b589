"""aprt's offline tools: reference model, export, conversion, golden data."""

__version__ = "0.1.0"
