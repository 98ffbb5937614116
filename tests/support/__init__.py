"""Helpers shared by the tests: policies, servers, browsers and store fixtures (no tests here)."""
