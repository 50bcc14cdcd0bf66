-- Sets the phase label of a stored result, the numbers it was decided on and the verdict on it.
-- ?1: job id, ?2: phase, ?3: decided_on (JSON; the verdict is its `settling.verdict`)
UPDATE results SET phase = ?2, decided_on = ?3, verdict = json_extract(?3, '$.settling.verdict')
WHERE job_id = ?1
