-- Deletes a job row.
-- ?1: job id
DELETE FROM jobs WHERE id = ?1
