-- The runners with run rows still open (no outcome: running, or interrupted).
SELECT DISTINCT owner FROM runs WHERE outcome IS NULL
