//! The schema migrations of both backends, compiled into the binary: the files of
//! `migrations/sqlite` and `migrations/postgres`, applied by sqlx's migrator in
//! the order of their numbers, each checked against the checksum of its SQL that
//! the database recorded when it applied it. (`sqlx::migrate!` builds the same
//! list through sqlx's macros, whose build compiles sqlx, its drivers and tokio a
//! second time, for the compiler: about a minute of a build from scratch.) A new
//! migration is a new file and a new line here; a unit test checks that the two
//! agree.

use sqlx::migrate::{Migration, MigrationType, Migrator};
use sqlx::{AssertSqlSafe, SqlSafeStr};

/// One migration file: its name (`<version>_<description>.sql`) and its SQL.
type File = (&'static str, &'static str);

pub const SQLITE: &[File] = &[
    ("0001_init.sql", include_str!("../../../migrations/sqlite/0001_init.sql")),
    ("0002_inputs.sql", include_str!("../../../migrations/sqlite/0002_inputs.sql")),
    ("0003_leases.sql", include_str!("../../../migrations/sqlite/0003_leases.sql")),
    ("0004_open_jobs.sql", include_str!("../../../migrations/sqlite/0004_open_jobs.sql")),
    ("0005_blobs.sql", include_str!("../../../migrations/sqlite/0005_blobs.sql")),
    ("0006_keys.sql", include_str!("../../../migrations/sqlite/0006_keys.sql")),
    ("0007_deletes_storage.sql", include_str!("../../../migrations/sqlite/0007_deletes_storage.sql")),
    ("0008_surgeries.sql", include_str!("../../../migrations/sqlite/0008_surgeries.sql")),
];

pub const POSTGRES: &[File] = &[
    ("0001_init.sql", include_str!("../../../migrations/postgres/0001_init.sql")),
    ("0002_open_jobs.sql", include_str!("../../../migrations/postgres/0002_open_jobs.sql")),
    ("0003_blobs.sql", include_str!("../../../migrations/postgres/0003_blobs.sql")),
    ("0004_keys.sql", include_str!("../../../migrations/postgres/0004_keys.sql")),
    ("0005_deletes_storage.sql", include_str!("../../../migrations/postgres/0005_deletes_storage.sql")),
    ("0006_surgeries.sql", include_str!("../../../migrations/postgres/0006_surgeries.sql")),
];

/// The migrator of a backend's files, with the versions, descriptions and
/// checksums that sqlx gives a folder of them.
pub fn migrator(files: &[File]) -> Migrator {
    Migrator::with_migrations(
        files
            .iter()
            .map(|(name, sql)| {
                let (version, rest) = name.split_once('_').expect("<version>_<description>.sql");
                let description = rest.trim_end_matches(".sql").replace('_', " ");
                Migration::new(
                    version.parse().expect("a numbered migration"),
                    description.into(),
                    MigrationType::Simple,
                    AssertSqlSafe(*sql).into_sql_str(),
                    sql.starts_with("-- no-transaction"),
                )
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Each backend's list holds every file of its folder, in order, with the text
    /// on disk, and sqlx reads the folder into the same migrations.
    #[test]
    fn the_lists_are_the_folders() {
        for (dir, files) in [("sqlite", SQLITE), ("postgres", POSTGRES)] {
            let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("migrations").join(dir);
            let mut names: Vec<String> =
                std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
            names.sort();
            assert_eq!(names, files.iter().map(|f| f.0).collect::<Vec<_>>(), "{dir}");
            for (name, sql) in files {
                assert_eq!(std::fs::read_to_string(folder.join(name)).unwrap(), *sql, "{dir}/{name}");
            }
            let rt = tokio::runtime::Builder::new_current_thread().build().unwrap();
            let read = rt.block_on(Migrator::new(folder.as_path())).unwrap();
            let ours = migrator(files);
            assert_eq!(read.migrations.len(), ours.migrations.len());
            for (a, b) in read.migrations.iter().zip(ours.migrations.iter()) {
                assert_eq!(
                    (a.version, &a.description, a.migration_type, &a.checksum, a.no_tx),
                    (b.version, &b.description, b.migration_type, &b.checksum, b.no_tx),
                    "{dir}"
                );
            }
        }
    }
}
