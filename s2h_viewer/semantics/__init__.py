"""Semantics of a hand pose: ASM, distance matrix, weights, losses, contacts and metrics."""

from s2h_viewer.semantics.anatomy import anatomical_loss, violation_rate
from s2h_viewer.semantics.asm import distance_matrix, palm_anchors, semantic_matrix
from s2h_viewer.semantics.contacts import CONTACT_PAIRS, contact_gaps, detect_contacts
from s2h_viewer.semantics.metrics import RetargetScores, palm_and_finger_scores, score_retarget
from s2h_viewer.semantics.similarity import masked_cosine, semantic_similarity, semantic_weights

__all__ = ["CONTACT_PAIRS", "RetargetScores", "anatomical_loss", "contact_gaps", "detect_contacts",
           "distance_matrix", "masked_cosine", "palm_and_finger_scores", "palm_anchors", "score_retarget",
           "semantic_matrix", "semantic_similarity", "semantic_weights", "violation_rate"]
