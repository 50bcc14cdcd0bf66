-- Closes a run row with its end time and outcome.
-- ?1: run id, ?2: ended at, ?3: outcome
UPDATE runs SET ended_at = ?2, outcome = ?3 WHERE id = ?1
