-- Forgets the marks of a sweep's results not yet relabelled in a key range (one key, or every
-- key of the sweep after a relabelling of all its results).
-- ?1: the first key, ?2: the end of the range (excluded)
DELETE FROM meta WHERE key >= ?1 AND key < ?2
