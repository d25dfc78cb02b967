"""Helpers the tests share (sites, pages, pictures, scenes); no tests here."""
