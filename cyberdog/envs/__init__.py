"""Gymnasium environments (`CyberDog-v0`)."""
