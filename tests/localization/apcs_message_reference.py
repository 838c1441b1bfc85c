"""The no-match message of APCS's correction written when the correction is made: the form
:func:`sonar_gym.localization.apcs._match_and_correct` replaced with a message written when
first read, kept as the tests' reference (Yamamoto et al., Fig. 2, sec. 4.3)."""

from __future__ import annotations

from sonar_gym.localization.apcs_walls import AMBIGUOUS, MatchResult


def unmatched_message_eager(match: MatchResult) -> str:
    """The message of a correction not made for want of a unique match, as it was built."""
    reasons = match.checks.rejection_summary()
    message = (
        "more than one map wall matches"
        if match.status == AMBIGUOUS
        else f"no map wall matches ({reasons})"
    )
    return message
