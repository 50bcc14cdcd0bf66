-- A job's status.
-- ?1: job id
SELECT status FROM jobs WHERE id = ?1
