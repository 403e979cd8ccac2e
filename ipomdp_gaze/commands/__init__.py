"""Subcommands of ``ipomdp-gaze``; shared argument helpers live in :mod:`.common`."""
