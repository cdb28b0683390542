"""Metrics as pure functions: text (:mod:`.text`: BLEU, ROUGE-L, CIDEr), motion
(:mod:`.motion`: APE, AVE and friends), the text-to-motion yardstick (:mod:`.t2m`:
R-precision, FID, MM-Dist, Diversity, MultiModality) and physical plausibility
(:mod:`.physics`: foot skating, floor penetration, root jumps)."""
