"""Shared pieces of the Dash pages: shell, design panel, URL state, figure style.

UI only: no numerics here (the pages get every number from shimmy.service.analyses).
"""
