//! Where the large bytes of a job live: uploaded inputs, checkpoints (with their
//! per-vertex fields) and result files, through the `object_store` crate — a
//! directory on this machine by default, or any S3-compatible bucket shared by
//! the nodes of a cluster. The database keeps only their keys.
//!
//! Keys, under the store's prefix: `jobs/{id}/inputs/{name}`,
//! `jobs/{id}/checkpoints/{iteration}.e{epoch}.json`, `jobs/{id}/context.json` and
//! `jobs/{id}/results/e{epoch}/{name}`. A key written under a lease carries its
//! epoch, so a worker that lost its lease never overwrites what the job's row
//! points to.

use futures_util::StreamExt;
use object_store::aws::AmazonS3Builder;
use object_store::local::LocalFileSystem;
use object_store::path::{Path, PathPart};
use object_store::{ObjectStore, ObjectStoreExt, PutPayload};
use std::sync::Arc;

/// A bucket (or directory) of blobs, with the prefix every key is under.
#[derive(Clone)]
pub struct Blobs {
    store: Arc<dyn ObjectStore>,
    prefix: Vec<String>,
    shown: String,
    /// The directory of a local store (whose emptied folders are removed).
    local: Option<std::path::PathBuf>,
}

impl std::fmt::Debug for Blobs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.shown)
    }
}

/// Why a blob could not be stored or read: the message names the key or setting.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BlobError(pub String);

pub type BlobResult<T> = Result<T, BlobError>;

fn blob_error(what: &str, key: &Path, e: object_store::Error) -> BlobError {
    BlobError(format!("{what} {key}: {e}"))
}

impl Blobs {
    /// Blobs in the local directory `dir` (created if missing).
    pub fn local(dir: &std::path::Path) -> BlobResult<Blobs> {
        std::fs::create_dir_all(dir)
            .map_err(|e| BlobError(format!("cannot create the blob directory {}: {e}", dir.display())))?;
        let store = LocalFileSystem::new_with_prefix(dir)
            .map_err(|e| BlobError(format!("blob directory {}: {e}", dir.display())))?;
        Ok(Blobs {
            store: Arc::new(store),
            prefix: Vec::new(),
            shown: dir.display().to_string(),
            local: Some(dir.into()),
        })
    }

    /// Blobs in an S3-compatible bucket: `url` is `s3://bucket` or
    /// `s3://bucket/prefix`. Credentials, region and endpoint come from the usual
    /// AWS variables (`AWS_ACCESS_KEY_ID`, `AWS_SECRET_ACCESS_KEY`, `AWS_REGION`,
    /// `AWS_ENDPOINT`, `AWS_ALLOW_HTTP=true` for a plain-HTTP endpoint).
    pub fn s3(url: &str) -> BlobResult<Blobs> {
        let rest = url
            .strip_prefix("s3://")
            .ok_or_else(|| BlobError(format!("--object-store {url:?}: expected s3://bucket or s3://bucket/prefix")))?;
        let mut parts = rest.split('/').filter(|p| !p.is_empty());
        let bucket =
            parts.next().ok_or_else(|| BlobError(format!("--object-store {url:?}: the bucket name is missing")))?;
        let prefix: Vec<String> = parts.map(str::to_string).collect();
        let store = AmazonS3Builder::from_env()
            .with_bucket_name(bucket)
            .build()
            .map_err(|e| BlobError(format!("--object-store {url}: {e}")))?;
        Ok(Blobs { store: Arc::new(store), prefix, shown: url.to_string(), local: None })
    }

    /// `--object-store` if given, else the directory `blobs` under `data_dir`.
    pub fn open(object_store: Option<&str>, data_dir: &std::path::Path) -> BlobResult<Blobs> {
        match object_store {
            Some(url) => Blobs::s3(url),
            None => Blobs::local(&data_dir.join("blobs")),
        }
    }

    /// The key of `parts` (each escaped as one path segment) under the prefix.
    fn key(&self, parts: &[&str]) -> Path {
        let segments = self.prefix.iter().map(String::as_str).chain(parts.iter().copied());
        Path::from_iter(segments.map(PathPart::from))
    }

    pub async fn put(&self, parts: &[&str], bytes: Vec<u8>) -> BlobResult<()> {
        let key = self.key(parts);
        self.store.put(&key, PutPayload::from(bytes)).await.map_err(|e| blob_error("cannot write", &key, e))?;
        Ok(())
    }

    /// The blob at `parts`; `None` if there is none.
    pub async fn get(&self, parts: &[&str]) -> BlobResult<Option<Vec<u8>>> {
        let key = self.key(parts);
        match self.store.get(&key).await {
            Ok(got) => Ok(Some(got.bytes().await.map_err(|e| blob_error("cannot read", &key, e))?.to_vec())),
            Err(object_store::Error::NotFound { .. }) => Ok(None),
            Err(e) => Err(blob_error("cannot read", &key, e)),
        }
    }

    /// The blob at `parts`, which a row of the database points to.
    pub async fn get_existing(&self, parts: &[&str]) -> BlobResult<Vec<u8>> {
        self.get(parts).await?.ok_or_else(|| BlobError(format!("the blob {} is missing", self.key(parts))))
    }

    /// The bytes of every blob under `parts` together.
    pub async fn size_all(&self, parts: &[&str]) -> BlobResult<u64> {
        let key = self.key(parts);
        let mut listed = self.store.list(Some(&key));
        let mut total = 0;
        while let Some(meta) = listed.next().await {
            total += meta.map_err(|e| blob_error("cannot list", &key, e))?.size;
        }
        Ok(total)
    }

    /// Remove every blob under `parts` (a job's folder, an old result set).
    pub async fn delete_all(&self, parts: &[&str]) -> BlobResult<()> {
        let key = self.key(parts);
        let listed = self.store.list(Some(&key)).map(|m| m.map(|m| m.location)).boxed();
        let mut deleted = self.store.delete_stream(listed);
        while let Some(r) = deleted.next().await {
            match r {
                Ok(_) | Err(object_store::Error::NotFound { .. }) => {}
                Err(e) => return Err(blob_error("cannot delete under", &key, e)),
            }
        }
        if let Some(root) = &self.local {
            // the folders the files were in (object keys have no folders to delete)
            let _ = std::fs::remove_dir_all(root.join(key.as_ref()));
        }
        Ok(())
    }
}

/// The blob key parts of a job's input `name`.
pub fn input_key<'a>(id: &'a str, name: &'a str) -> [&'a str; 4] {
    ["jobs", id, "inputs", name]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_local_store_keeps_escapes_and_deletes_by_folder() {
        let dir = tempfile::tempdir().unwrap();
        let blobs = Blobs::local(dir.path()).unwrap();
        blobs.put(&input_key("j1", "a/b c"), b"one".to_vec()).await.unwrap();
        blobs.put(&["jobs", "j1", "results", "e1", "shape.glb"], b"two".to_vec()).await.unwrap();
        blobs.put(&input_key("j2", "image"), b"three".to_vec()).await.unwrap();
        assert_eq!(blobs.get(&input_key("j1", "a/b c")).await.unwrap().unwrap(), b"one");
        assert_eq!(blobs.get(&input_key("j1", "nothing")).await.unwrap(), None);
        blobs.delete_all(&["jobs", "j1"]).await.unwrap();
        assert_eq!(blobs.get(&input_key("j1", "a/b c")).await.unwrap(), None);
        assert!(!dir.path().join("jobs/j1").exists(), "the emptied folder is gone");
        assert_eq!(blobs.get(&["jobs", "j1", "results", "e1", "shape.glb"]).await.unwrap(), None);
        assert_eq!(blobs.get(&input_key("j2", "image")).await.unwrap().unwrap(), b"three");
        assert!(matches!(blobs.get_existing(&input_key("j1", "x")).await, Err(BlobError(_))));
    }

    #[test]
    fn s3_urls_need_a_bucket() {
        assert!(Blobs::s3("s3://").is_err());
        assert!(Blobs::s3("gs://bucket").is_err());
    }
}
