"""The Design decisions page's three sections (sensitivities, optimiser, robustness), what they share and
the page's state in the address; pages/design.py lays them out."""
