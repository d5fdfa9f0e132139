#!/usr/bin/env python3
"""Fine-tune a small causal language model on the training data of `coherent export sft`
(docs/training.md): a LoRA adapter (PEFT) trained with TRL's SFTTrainer, the loss on the
answers only; the adapter merged into the model; the merged model written as Hugging
Face safetensors and as a GGUF file that llama.cpp's server loads, so that the tuned
model answers through the same OpenAI-compatible path as any other:

    coherent export sft native --method pefa --out data
    python examples/finetune.py --data data --base SmolLM2-135M-Instruct.Q4_1.gguf --out tuned
    python -m xllamacpp.server -m tuned/model.gguf ...   # or any llama.cpp server
    coherent run native --task 3 --base-url http://127.0.0.1:8080/v1 --model tuned

The model to start from is a GGUF file of the llama architecture (read with
transformers' GGUF support; its tokenizer and chat template are carried into the file
written) or a Hugging Face model folder or name (then only the safetensors are written:
llama.cpp's own converter makes the GGUF of any architecture). `--tiny` starts instead
from a randomly initialised model of a few layers with the base's tokenizer: the
recipe's own test, minutes on a CPU.

`--adapter DIR` trains nothing: it merges an adapter trained elsewhere (on a GPU machine,
say, whose `adapter/` folder is all that comes back) into the base and writes the same
files, so that the GGUF is made where the base file is. `--write-base` trains nothing
either: it writes the base itself to `model.gguf` with the same writer (float16), the fair
"before" of a before/after comparison.

Needs the `training` extra: torch, transformers, trl, peft, datasets, accelerate, gguf.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", type=Path, help="the folder `coherent export sft` wrote (not with --adapter)")
    p.add_argument("--base", required=True, help="a GGUF file, or a Hugging Face model folder or name")
    p.add_argument("--out", type=Path, required=True, help="folder for the adapter, the merged model and model.gguf")
    p.add_argument("--tiny", action="store_true", help="a randomly initialised 2-layer model with the base's tokenizer")
    p.add_argument("--max-steps", type=int, default=-1, help="optimizer steps (default: --epochs over the data)")
    p.add_argument("--epochs", type=float, default=1.0)
    p.add_argument("--max-minutes", type=float, default=0, help="stop training after this many minutes (0: no limit)")
    p.add_argument("--max-examples", type=int, default=0, help="train on the first N examples only (0: all)")
    p.add_argument("--batch-size", type=int, default=4)
    p.add_argument("--grad-accum", type=int, default=4)
    p.add_argument("--lr", type=float, default=2e-4)
    p.add_argument("--lora-r", type=int, default=16)
    p.add_argument("--lora-alpha", type=int, default=32)
    p.add_argument("--max-length", type=int, default=4096, help="longest example in tokens; longer ones are cut")
    p.add_argument("--threads", type=int, default=0, help="CPU threads for torch (0: torch's default)")
    p.add_argument("--bf16", action="store_true", help="bfloat16 mixed precision (a GPU that has it)")
    p.add_argument("--adapter", type=Path, help="merge this trained adapter folder instead of training")
    p.add_argument("--write-base", action="store_true", help="write the base as model.gguf, untrained")
    p.add_argument("--seed", type=int, default=0)
    return p.parse_args(argv)


def load_base(args: argparse.Namespace):
    """The model and tokenizer to start from, torch's threads set first (`--threads`)."""
    import torch
    from transformers import AutoModelForCausalLM, AutoTokenizer, LlamaConfig, LlamaForCausalLM

    if args.threads:
        torch.set_num_threads(args.threads)
    base = Path(args.base)
    gguf = base.suffix == ".gguf"
    where = dict(pretrained_model_name_or_path=str(base.parent), gguf_file=base.name) if gguf else dict(
        pretrained_model_name_or_path=args.base
    )
    tokenizer = AutoTokenizer.from_pretrained(**where)
    if tokenizer.pad_token is None:
        tokenizer.pad_token = tokenizer.eos_token
    if args.tiny:
        torch.manual_seed(args.seed)
        config = LlamaConfig(
            vocab_size=len(tokenizer),
            hidden_size=64,
            intermediate_size=128,
            num_hidden_layers=2,
            num_attention_heads=4,
            num_key_value_heads=2,
            max_position_embeddings=8192,
            tie_word_embeddings=True,
            bos_token_id=tokenizer.bos_token_id,
            eos_token_id=tokenizer.eos_token_id,
            pad_token_id=tokenizer.pad_token_id,
        )
        model = LlamaForCausalLM(config)
    else:
        model = AutoModelForCausalLM.from_pretrained(**where, dtype=torch.float32)
        if gguf:
            # transformers dequantises a GGUF file's weights into float32 as it loads
            # them, yet marks the model as quantized, which its trainer refuses: the
            # weights trained are those float32 ones.
            model.hf_quantizer = None
            model.is_quantized = False
            model.config.__dict__.pop("quantization_config", None)
    return model, tokenizer


def load_data(args: argparse.Namespace):
    """The train split as it is: TRL reads its conversational prompt and completion (the
    other columns say where each example comes from)."""
    from datasets import load_dataset

    data = load_dataset("json", data_files={"train": str(args.data / "train.jsonl")})
    data["train"] = data["train"].shuffle(seed=args.seed)
    if args.max_examples:
        data["train"] = data["train"].select(range(min(args.max_examples, len(data["train"]))))
    return data


def train(args: argparse.Namespace) -> dict:
    """Trains, merges and writes; returns what the run measured."""
    import torch
    from peft import LoraConfig
    from trl import SFTConfig, SFTTrainer

    start = time.time()
    model, tokenizer = load_base(args)
    data = load_data(args)
    config = SFTConfig(
        output_dir=str(args.out / "checkpoints"),
        max_steps=args.max_steps,
        num_train_epochs=args.epochs,
        per_device_train_batch_size=args.batch_size,
        gradient_accumulation_steps=args.grad_accum,
        learning_rate=args.lr,
        lr_scheduler_type="cosine",
        warmup_steps=0.03,
        logging_steps=1,
        save_strategy="no",
        eval_strategy="no",
        report_to="none",
        max_length=args.max_length,
        completion_only_loss=True,
        seed=args.seed,
        bf16=args.bf16,
        use_cpu=not torch.cuda.is_available(),
        dataloader_num_workers=0,
    )
    lora = LoraConfig(
        r=args.lora_r,
        lora_alpha=args.lora_alpha,
        lora_dropout=0.0,
        target_modules=["q_proj", "k_proj", "v_proj", "o_proj", "gate_proj", "up_proj", "down_proj"],
        task_type="CAUSAL_LM",
    )
    trainer = SFTTrainer(
        model=model,
        args=config,
        train_dataset=data["train"],
        processing_class=tokenizer,
        peft_config=lora,
        callbacks=[deadline(args.max_minutes)] if args.max_minutes else None,
    )
    trainer.train()
    losses = [e["loss"] for e in trainer.state.log_history if "loss" in e]
    trainer.model.save_pretrained(str(args.out / "adapter"))
    report = {
        "examples": len(data["train"]),
        "steps": trainer.state.global_step,
        "examples_seen": trainer.state.global_step * args.batch_size * args.grad_accum,
        "first_loss": losses[0] if losses else None,
        "last_loss": losses[-1] if losses else None,
        "losses": losses,
        "device": torch.cuda.get_device_name() if torch.cuda.is_available() else "cpu",
    }
    return finish(args, trainer.model, tokenizer, report, start)


def merge(args: argparse.Namespace) -> dict:
    """Merges the trained adapter `args.adapter` into the base and writes the files that
    training writes; the report of the training, where the adapter has one, is kept."""
    from peft import PeftModel

    start = time.time()
    model, tokenizer = load_base(args)
    tuned = PeftModel.from_pretrained(model, str(args.adapter))
    trained = args.adapter.parent / "train_report.json"
    report = json.loads(trained.read_text()) if trained.is_file() else {}
    report["merged_from"] = str(args.adapter)
    if args.adapter.resolve() != (args.out / "adapter").resolve():
        tuned.save_pretrained(str(args.out / "adapter"))
    return finish(args, tuned, tokenizer, report, start)


def finish(args: argparse.Namespace, tuned, tokenizer, report: dict, start: float) -> dict:
    """The adapter of `tuned` merged into its model; the merged model written as safetensors
    and, from a GGUF base, as `model.gguf`; `train_report.json` written."""
    merged = tuned.merge_and_unload()
    merged.save_pretrained(str(args.out / "merged"))
    tokenizer.save_pretrained(str(args.out / "merged"))
    written = None
    if Path(args.base).suffix == ".gguf":
        written = str(write_gguf(merged, Path(args.base), args.out / "model.gguf"))
    # The seconds of the training, or of the merge where the adapter was trained elsewhere.
    report["merge_seconds" if "merged_from" in report else "seconds"] = round(time.time() - start, 1)
    report = {
        "base": str(args.base),
        "tiny": args.tiny,
        **report,
        "gguf": written,
        "settings": report.get("settings") or {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
    }
    (args.out / "train_report.json").write_text(json.dumps(report, indent=2) + "\n")
    return report


def deadline(minutes: float):
    """A callback that ends training at the first step after `minutes` of it."""
    from transformers import TrainerCallback

    class Deadline(TrainerCallback):
        def on_train_begin(self, args, state, control, **kwargs):
            self.start = time.time()

        def on_step_end(self, args, state, control, **kwargs):
            if time.time() - self.start > minutes * 60:
                control.should_training_stop = True

    return Deadline()


# The tensors of a llama-architecture model as Hugging Face names them, and as GGUF does
# (llama.cpp's names for the llama architecture).
_LAYER_TENSORS = {
    "input_layernorm.weight": "attn_norm.weight",
    "self_attn.q_proj.weight": "attn_q.weight",
    "self_attn.k_proj.weight": "attn_k.weight",
    "self_attn.v_proj.weight": "attn_v.weight",
    "self_attn.o_proj.weight": "attn_output.weight",
    "post_attention_layernorm.weight": "ffn_norm.weight",
    "mlp.gate_proj.weight": "ffn_gate.weight",
    "mlp.up_proj.weight": "ffn_up.weight",
    "mlp.down_proj.weight": "ffn_down.weight",
}
_MODEL_TENSORS = {
    "model.embed_tokens.weight": "token_embd.weight",
    "model.norm.weight": "output_norm.weight",
    "lm_head.weight": "output.weight",
}


def gguf_name(name: str) -> str:
    """The GGUF name of a Hugging Face tensor name of the llama architecture."""
    if name in _MODEL_TENSORS:
        return _MODEL_TENSORS[name]
    parts = name.split(".", 3)
    if len(parts) == 4 and parts[:2] == ["model", "layers"] and parts[3] in _LAYER_TENSORS:
        return f"blk.{parts[2]}.{_LAYER_TENSORS[parts[3]]}"
    raise ValueError(f"{name}: not a tensor of the llama architecture")


def rotary_rows(weight, heads: int):
    """The rows of a query or key projection reordered for llama.cpp's rotary embedding:
    transformers rotates the two halves of each head's dimensions, llama.cpp rotates
    neighbouring pairs, so each head's rows go from (half, i) order to (i, half) order."""
    rows, *rest = weight.shape
    return weight.reshape(heads, 2, rows // heads // 2, *rest).swapaxes(1, 2).reshape(weight.shape)


def write_gguf(model, tokenizer_gguf: Path, path: Path) -> Path:
    """`model` (llama architecture) as a GGUF file at `path`: its hyperparameters from its
    config, the tokenizer and chat template copied from `tokenizer_gguf`, the matrices in
    float16 and the norms in float32."""
    import numpy as np
    from gguf import GGUFReader, GGUFValueType, GGUFWriter

    cfg = model.config
    if cfg.model_type != "llama":
        raise ValueError(f"model type {cfg.model_type!r}: this writer knows the llama architecture only")
    heads, kv_heads = cfg.num_attention_heads, cfg.num_key_value_heads
    head_dim = getattr(cfg, "head_dim", None) or cfg.hidden_size // heads
    rope = getattr(cfg, "rope_theta", None) or (getattr(cfg, "rope_parameters", None) or {}).get("rope_theta", 10000.0)
    tmp = path.with_name(f".{path.name}.tmp")
    writer = GGUFWriter(str(tmp), arch="llama")
    writer.add_name(f"coherent fine-tune of {tokenizer_gguf.stem}")
    writer.add_context_length(cfg.max_position_embeddings)
    writer.add_embedding_length(cfg.hidden_size)
    writer.add_block_count(cfg.num_hidden_layers)
    writer.add_feed_forward_length(cfg.intermediate_size)
    writer.add_head_count(heads)
    writer.add_head_count_kv(kv_heads)
    writer.add_rope_dimension_count(head_dim)
    writer.add_rope_freq_base(float(rope))
    writer.add_layer_norm_rms_eps(float(cfg.rms_norm_eps))
    writer.add_vocab_size(cfg.vocab_size)
    writer.add_file_type(1)  # mostly float16
    reader = GGUFReader(str(tokenizer_gguf))
    for key, field in reader.fields.items():
        if not key.startswith("tokenizer."):
            continue
        vtype = field.types[0]
        sub = field.types[-1] if vtype == GGUFValueType.ARRAY else None
        writer.add_key_value(key, field.contents(), vtype, sub_type=sub)
    state = model.state_dict()
    for name, tensor in state.items():
        if name == "lm_head.weight" and cfg.tie_word_embeddings:
            continue
        data = tensor.detach().float().cpu().numpy()
        if name.endswith("self_attn.q_proj.weight"):
            data = rotary_rows(data, heads)
        elif name.endswith("self_attn.k_proj.weight"):
            data = rotary_rows(data, kv_heads)
        data = data.astype(np.float32 if data.ndim == 1 else np.float16)
        writer.add_tensor(gguf_name(name), np.ascontiguousarray(data))
    writer.write_header_to_file()
    writer.write_kv_data_to_file()
    writer.write_tensors_to_file()
    writer.close()
    os.replace(tmp, path)
    return path


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    if args.write_base:
        if Path(args.base).suffix != ".gguf":
            print(f"error: --write-base needs a GGUF --base (its tokenizer is copied), not {args.base}", file=sys.stderr)
            return 2
        model, _ = load_base(args)
        print(f"wrote {write_gguf(model, Path(args.base), args.out / 'model.gguf')}")
        return 0
    if args.adapter:
        if not (args.adapter / "adapter_config.json").is_file():
            print(f"error: --adapter {args.adapter}: no adapter_config.json in it", file=sys.stderr)
            return 2
        report = merge(args)
        print(f"merged {args.adapter} into {args.base}")
        if report["gguf"]:
            print(f"wrote {report['gguf']}")
        return 0
    if args.data is None:
        print("error: --data is needed (the folder `coherent export sft` wrote), or --adapter", file=sys.stderr)
        return 2
    examples = args.data / "train.jsonl"
    if not examples.is_file() or examples.stat().st_size == 0:
        print(f"error: {examples} is missing or empty: `coherent export sft` writes it", file=sys.stderr)
        return 2
    report = train(args)
    first, last = report["first_loss"], report["last_loss"]
    print(
        f"trained {report['steps']} steps on {report['examples']} examples in {report['seconds']} s; "
        f"loss {first:.3f} -> {last:.3f}" if first is not None and not math.isnan(first) else "no loss logged"
    )
    if report["gguf"]:
        print(f"wrote {report['gguf']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
