"""Verification: frequency responses from time histories, envelope checks, time-domain metrics and equivalent delays."""
