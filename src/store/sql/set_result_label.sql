-- Sets the phase label of a stored result and the numbers it was decided on.
-- ?1: job id, ?2: phase, ?3: decided_on (JSON)
UPDATE results SET phase = ?2, decided_on = ?3 WHERE job_id = ?1
