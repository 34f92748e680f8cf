"""The package version: a ground-floor module every layer may import (the package root imports the
analyses, so nothing inside the package imports the root)."""

__version__ = "0.1.0"
