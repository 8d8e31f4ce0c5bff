//! `shapeflow keys create | list | revoke`: the API keys of a store.

use super::args::{KeysAction, StoreArgs};
use super::serve::redact;
use anyhow::{Context, Result};

/// `shapeflow keys ...` on the store of `args`.
pub(crate) fn keys(action: KeysAction, args: &StoreArgs) -> Result<()> {
    use shapeflow::service::keys;
    let database = args.database()?;
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    rt.block_on(async {
        let blobs = shapeflow::service::blobs::Blobs::open(args.object_store.as_deref(), &args.data_dir)?;
        let store = shapeflow::service::store::open(&database, blobs)
            .await
            .with_context(|| format!("cannot open database {}", redact(&database)))?;
        match action {
            KeysAction::Create { name, admin, max_active, max_storage } => {
                let grant = keys::Grant {
                    admin,
                    max_active: max_active.map(i64::from),
                    max_storage: max_storage.map(|b| b.min(i64::MAX as u64) as i64),
                };
                let key = keys::create(&store, &name, grant).await?;
                println!("created the key {name:?}; it is shown only now:");
                println!("{key}");
            }
            KeysAction::List => {
                for k in store.keys().await? {
                    let quota = k.max_active.map_or("-".to_string(), |n| n.to_string());
                    let storage = k.max_storage.map_or("-".to_string(), |n| shapeflow::jobs::format_size(n as u64));
                    let state = if k.revoked { "revoked" } else { "active" };
                    println!(
                        "{}\t{}\tmax-active {quota}\tmax-storage {storage}\t{}\t{state}",
                        k.name,
                        if k.admin { "admin" } else { "user" },
                        k.created_at
                    );
                }
            }
            KeysAction::Revoke { name } => {
                anyhow::ensure!(store.revoke_key(&name).await?, "no key {name:?} to revoke (or it is revoked already)");
                println!("revoked the key {name:?}");
            }
        }
        Ok(())
    })
}
