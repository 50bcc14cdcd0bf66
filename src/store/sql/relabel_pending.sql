-- The meta keys of a sweep's results not yet relabelled (`relabel:<sweep id>:<job id>`).
-- ?1: the key prefix `relabel:<sweep id>:`, ?2: the prefix with its last character raised
SELECT key FROM meta WHERE key >= ?1 AND key < ?2
